// `pliant cloth` on a garment: an OBJ in centimetres with quads, UVs, normals, groups and a
// material library, two panels sewn together, a fabric preset; frames keep the input's faces,
// the material library is copied beside them, and cloth.pc2 holds every frame. A quad PLY garment
// with UVs and properties gives PLY frames with the same faces, UVs and properties, and cloth.mdd
// holds every frame.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "integration/body_checks.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/obj_polygons.hpp"
#include "pliant/io/ply_polygons.hpp"
#include "run_cli.hpp"

namespace pliant::test {
namespace {

void write(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// Two panels of N × N quads, 20 cm square, 5 cm apart along x, in centimetres; UVs per vertex,
// one normal, groups "left"/"right", materials "red"/"blue".
constexpr int N = 4;
std::string garment_obj() {
    std::ostringstream obj;
    obj << "mtllib skirt.mtl\no skirt\n";
    for (int panel = 0; panel < 2; ++panel) {
        for (int j = 0; j <= N; ++j) {
            for (int i = 0; i <= N; ++i) {
                obj << "v " << (panel * 25.0 + i * 20.0 / N) << " " << (j * 20.0 / N) << " 50\n";
            }
        }
    }
    for (int j = 0; j <= N; ++j) {
        for (int i = 0; i <= N; ++i) {
            obj << "vt " << static_cast<double>(i) / N << " " << static_cast<double>(j) / N << "\n";
        }
    }
    obj << "vn 0 0 1\n";
    for (int panel = 0; panel < 2; ++panel) {
        obj << (panel == 0 ? "g left\nusemtl red\n" : "g right\nusemtl blue\n");
        const int base = panel * (N + 1) * (N + 1);
        for (int j = 0; j < N; ++j) {
            for (int i = 0; i < N; ++i) {
                const int c[4] = {j * (N + 1) + i, j * (N + 1) + i + 1, (j + 1) * (N + 1) + i + 1,
                                  (j + 1) * (N + 1) + i};
                obj << "f";
                for (const int k : c) {
                    obj << " " << base + k + 1 << "/" << k + 1 << "/1";
                }
                obj << "\n";
            }
        }
    }
    return obj.str();
}

// The `f` (corners as v/vt: the normals are recomputed per vertex), `g`, `o`, `usemtl` and
// `mtllib` lines of an OBJ, in order.
std::vector<std::string> structure(const std::string& text) {
    std::vector<std::string> lines;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("f ", 0) == 0) {
            std::istringstream corners(line.substr(2));
            std::string face = "f";
            for (std::string c; corners >> c;) {
                face.push_back(' ');
                face.append(c, 0, c.rfind('/'));
            }
            lines.push_back(face);
        } else if (line.rfind("g ", 0) == 0 || line.rfind("o ", 0) == 0 ||
                   line.rfind("usemtl ", 0) == 0 || line.rfind("mtllib ", 0) == 0) {
            lines.push_back(line);
        }
    }
    return lines;
}

std::vector<float> v_lines(const std::string& text) {
    std::vector<float> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("v ", 0) == 0) {
            std::istringstream v(line.substr(2));
            double x = 0;
            double y = 0;
            double z = 0;
            v >> x >> y >> z;
            out.insert(out.end(),
                       {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
        }
    }
    return out;
}

TEST(GarmentCommand, FramesKeepTheGarmentAndThePointCacheHoldsThem) {
    ScratchDir scratch;
    write(scratch / "skirt.obj", garment_obj());
    write(scratch / "skirt.mtl", "newmtl red\nKd 1 0 0\nnewmtl blue\nKd 0 0 1\n");
    // The left panel's right column sewn to the right panel's left column.
    std::string a;
    std::string b;
    for (int j = 0; j <= N; ++j) {
        if (j > 0) {
            a.append(", ");
            b.append(", ");
        }
        a.append(std::to_string(j * (N + 1) + N));
        b.append(std::to_string((N + 1) * (N + 1) + j * (N + 1)));
    }
    write(scratch / "scene.json", R"({
        "cloth": {"mesh": "skirt.obj", "units": "cm"},
        "material": "cotton",
        "seams": [{"a": [)" + a + R"(], "b": [)" +
                                      b + R"(], "seconds": 0.2}],
        "pins": {"vertices": [0, 20]},
        "fps": 24, "frames": 6, "substeps": 20,
        "output": {"point_cache": "pc2"}
    })");
    const CliResult r = run_cli("--json cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err.find("implausible"), std::string::npos) << r.err;  // units given
    // The panels are placed 5 cm apart, 5 cm edges: sewing stretches the edges beside the seam.
    EXPECT_NE(r.err.find("scene.json: seams[0]: pair "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("sewing stretches the edges beside it by about"), std::string::npos)
        << r.err;
    const nlohmann::json stats = nlohmann::json::parse(r.out);
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);

    const std::string input = read_text(scratch / "skirt.obj");
    const std::filesystem::path frames = scratch / "out" / "frames";
    const std::string first = read_text(frames / "frame_0000.obj");
    const std::string last = read_text(frames / "frame_0006.obj");
    EXPECT_EQ(structure(first), structure(input));
    EXPECT_EQ(structure(last), structure(input));
    EXPECT_NE(last.find("\nvt 0.25 0.5\n"), std::string::npos);
    EXPECT_NE(last.find("\nvn "), std::string::npos);
    EXPECT_EQ(read_text(frames / "skirt.mtl"), read_text(scratch / "skirt.mtl"));
    // Frame 0 in metres: centimetres scaled.
    const std::vector<float> start = v_lines(first);
    EXPECT_FLOAT_EQ(start[2], 0.5F);
    EXPECT_FLOAT_EQ(start[3 * N], 0.2F);

    // The seam pulled the panels together (5 cm apart at the start).
    const std::vector<float> end = v_lines(last);
    const auto gap = [&](const std::vector<float>& p, int j) {
        const int va = j * (N + 1) + N;
        const int vb = (N + 1) * (N + 1) + j * (N + 1);
        const float dx = p[3 * vb] - p[3 * va];
        const float dy = p[3 * vb + 1] - p[3 * va + 1];
        const float dz = p[3 * vb + 2] - p[3 * va + 2];
        return std::sqrt(dx * dx + dy * dy + dz * dz);
    };
    EXPECT_NEAR(gap(start, 2), 0.05F, 1e-6F);
    EXPECT_LT(gap(end, 2), 0.01F);

    // cloth.pc2: header, then 7 samples; the last is frame 6 as float.
    ASSERT_EQ(stats.at("point_cache"), (scratch / "out" / "cloth.pc2").string());
    const std::string pc2 = read_text(scratch / "out" / "cloth.pc2");
    const std::size_t points = 2 * (N + 1) * (N + 1);
    ASSERT_EQ(pc2.size(), 32 + 7 * points * 12);
    EXPECT_EQ(pc2.substr(0, 12), std::string("POINTCACHE2\0", 12));
    std::int32_t header[2];
    std::memcpy(header, pc2.data() + 12, 8);
    EXPECT_EQ(header[0], 1);
    EXPECT_EQ(header[1], static_cast<std::int32_t>(points));
    float rates[2];
    std::memcpy(rates, pc2.data() + 20, 8);
    EXPECT_EQ(rates[0], 0.0F);
    EXPECT_EQ(rates[1], 1.0F);
    std::int32_t samples = 0;
    std::memcpy(&samples, pc2.data() + 28, 4);
    EXPECT_EQ(samples, 7);
    std::vector<float> cached(3 * points);
    std::memcpy(cached.data(), pc2.data() + 32 + 6 * points * 12, points * 12);
    EXPECT_EQ(cached, end);
}

TEST(GarmentCommand, CentimetresWithoutUnitsWarn) {
    ScratchDir scratch;
    write(scratch / "skirt.obj", garment_obj());
    write(scratch / "scene.json", R"({"cloth": {"mesh": "skirt.obj"}, "frames": 0})");
    const CliResult r = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("implausible for cloth"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("cloth.units"), std::string::npos) << r.err;
    // The material library is missing: a warning, the frames keep the mtllib line.
    EXPECT_NE(r.err.find("skirt.mtl is not copied"), std::string::npos) << r.err;
    EXPECT_NE(read_text(scratch / "out" / "frames" / "frame_0000.obj").find("mtllib skirt.mtl"),
              std::string::npos);
}

// The built-in skirt (scenes/garment, pipeline/garment_scene.hpp) on the walking mannequin over
// one walk cycle (1.5 s): intersection-free in every frame, no cloth vertex inside the body, no
// cloth edge through its surface and no body edge through the cloth at that frame's time
// (body_checks.hpp; the body's 12 frames at 8 fps interpolated here as the scene asks), the legs in
// contact with the skirt, and the cotton held near its length (edge strain p99 below 3 %).
TEST(GarmentCommand, SkirtOnTheWalkingBodyStaysOutsideItAndNearItsLength) {
    ScratchDir scratch;
    const std::filesystem::path dir =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / "garment";
    constexpr int FRAMES = 36;
    const CliResult r = run_cli("cloth " + quoted(dir / "scene.json") + " --no-preview --frames " +
                                    std::to_string(FRAMES) + " --out " + quoted(scratch / "out"),
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / "out" / "stats.json"));
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
    EXPECT_LT(stats.at("max_strain_p99").get<double>(), 0.03);
    std::int64_t contacts = 0;
    for (const nlohmann::json& frame : stats.at("frames")) {
        EXPECT_EQ(frame.at("intersecting_pairs"), 0) << frame.at("frame");
        EXPECT_EQ(frame.at("obstacle_intersections"), 0) << frame.at("frame");
        contacts += frame.at("obstacle_contacts").get<std::int64_t>();
    }
    EXPECT_GT(contacts, 0);

    constexpr int BODY_FRAMES = 12;
    constexpr double BODY_FPS = 8.0;
    std::vector<geometry::TriangleMeshD> body;
    for (int k = 0; k < BODY_FRAMES; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d.obj", k);
        body.push_back(io::read_mesh(dir / "body" / name));
    }
    geometry::TriangleMeshD skirt = io::triangulate(io::read_obj_polygons(dir / "skirt.obj"));
    for (int f = 0; f <= FRAMES; ++f) {
        const double u = f / 24.0 * BODY_FPS;
        const int k = static_cast<int>(std::floor(u));
        const double w = u - k;
        geometry::TriangleMeshD at = body[static_cast<std::size_t>(k % BODY_FRAMES)];
        const geometry::TriangleMeshD& next = body[static_cast<std::size_t>((k + 1) % BODY_FRAMES)];
        for (std::size_t v = 0; v < at.positions.size(); ++v) {
            at.positions[v] = at.positions[v] * (1.0 - w) + next.positions[v] * w;
        }
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d.obj", f);
        // The frame's positions on the solver's triangles (the quads split as the solver splits
        // them, along their shorter diagonal at rest).
        skirt.positions = io::read_mesh(scratch / "out" / "frames" / name).positions;
        EXPECT_EQ(vertices_inside(skirt, at), 0) << "frame " << f << ": skirt vertices inside";
        EXPECT_EQ(edges_crossing(skirt, at), 0) << "frame " << f << ": skirt edges through it";
        EXPECT_EQ(edges_crossing(at, skirt), 0) << "frame " << f << ": body edges through skirt";
    }
}

// The skirt with fewer substeps or a thinner fabric than the scene's: where, before the
// self-contacts' pushes were kept out of the body and the body's vertices swept against the
// cloth's triangles (mesh_contact.hpp), a skirt edge crossed the swinging arm (10 substeps, frame
// 38: 12 intersecting pairs) and a tip of the body entered a skirt triangle (30 substeps, 3 mm,
// frame 19: 6 pairs). Every frame's exact count (stats.json) is checked.
TEST(GarmentCommand, SkirtStaysOutOfTheBodyAtOtherSubstepsAndThicknesses) {
    ScratchDir scratch;
    const std::filesystem::path dir =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / "garment";
    nlohmann::json scene = nlohmann::json::parse(read_text(dir / "scene.json"));
    scene["cloth"]["mesh"] = (dir / "skirt.obj").string();
    scene["obstacles"][0]["mesh"]["frames"] = (dir / "body" / "frame_%04d.obj").string();
    struct Variant {
        int substeps;
        double thickness;
        int frames;
    };
    for (const Variant& v : {Variant{10, 0.005, 40}, Variant{30, 0.003, 20}}) {
        scene["substeps"] = v.substeps;
        scene["material"]["thickness"] = v.thickness;
        const std::string name = "skirt_" + std::to_string(v.substeps);
        write(scratch / (name + ".json"), scene.dump());
        const CliResult r =
            run_cli("cloth " + quoted(scratch / (name + ".json")) + " --no-preview --frames " +
                        std::to_string(v.frames) + " --out " + quoted(scratch / name),
                    scratch);
        ASSERT_EQ(r.exit_code, 0) << r.err;
        const nlohmann::json stats =
            nlohmann::json::parse(read_text(scratch / name / "stats.json"));
        EXPECT_EQ(stats.at("max_intersecting_pairs"), 0) << name;
        EXPECT_EQ(stats.at("max_obstacle_intersections"), 0) << name;
        for (const nlohmann::json& frame : stats.at("frames")) {
            EXPECT_EQ(frame.at("obstacle_intersections"), 0)
                << name << " frame " << frame.at("frame");
        }
    }
}

// The built-in skirt (scenes/garment): bitwise the same frames and point cache for 1 and 2
// threads, and after a resume.
TEST(GarmentCommand, SkirtIsDeterministicAndResumes) {
    ScratchDir scratch;
    const std::filesystem::path scene =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / "garment" / "scene.json";
    const auto run = [&](const std::string& options) {
        const CliResult r = run_cli("cloth " + quoted(scene) + " --no-preview " + options, scratch);
        EXPECT_EQ(r.exit_code, 0) << r.err;
    };
    run("--threads 1 --frames 4 --out " + quoted(scratch / "one"));
    run("--threads 2 --frames 4 --out " + quoted(scratch / "two"));
    run("--frames 2 --checkpoint-every 2 --out " + quoted(scratch / "resumed"));
    run("--frames 4 --resume --out " + quoted(scratch / "resumed"));
    const std::string last = read_text(scratch / "one" / "frames" / "frame_0004.obj");
    ASSERT_FALSE(last.empty());
    EXPECT_EQ(read_text(scratch / "two" / "frames" / "frame_0004.obj"), last);
    EXPECT_EQ(read_text(scratch / "resumed" / "frames" / "frame_0004.obj"), last);
    const std::string cache = read_text(scratch / "one" / "cloth.pc2");
    EXPECT_EQ(cache.size(), 32U + 5U * 1250U * 12U);
    EXPECT_EQ(read_text(scratch / "two" / "cloth.pc2"), cache);
    EXPECT_EQ(read_text(scratch / "resumed" / "cloth.pc2"), cache);
}

// One panel of M × M quads, 40 cm square, 50 cm up, as an ASCII PLY: UVs (s, t) and a float
// `quality` per vertex, a uchar `panel` per face.
constexpr int M = 4;
std::string garment_ply() {
    std::ostringstream ply;
    ply << "ply\nformat ascii 1.0\nelement vertex " << (M + 1) * (M + 1)
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float s\n"
           "property float t\nproperty float quality\nelement face "
        << M * M << "\nproperty list uchar int vertex_indices\nproperty uchar panel\nend_header\n";
    for (int j = 0; j <= M; ++j) {
        for (int i = 0; i <= M; ++i) {
            ply << i * 0.4 / M << " " << j * 0.4 / M << " 0.5 " << static_cast<double>(i) / M << " "
                << static_cast<double>(j) / M << " " << j * (M + 1) + i << "\n";
        }
    }
    for (int j = 0; j < M; ++j) {
        for (int i = 0; i < M; ++i) {
            ply << "4 " << j * (M + 1) + i << " " << j * (M + 1) + i + 1 << " "
                << (j + 1) * (M + 1) + i + 1 << " " << (j + 1) * (M + 1) + i << " " << (i + j) % 3
                << "\n";
        }
    }
    return ply.str();
}

// Big-endian words of an MDD file, decoded byte by byte.
std::uint32_t big_endian_word(const std::string& bytes, std::size_t at) {
    std::uint32_t w = 0;
    for (std::size_t k = 0; k < 4; ++k) {
        w = (w << 8) | static_cast<unsigned char>(bytes.at(at + k));
    }
    return w;
}

TEST(GarmentCommand, QuadPlyGarmentGivesPlyFramesAndAnMddCache) {
    ScratchDir scratch;
    write(scratch / "panel.ply", garment_ply());
    write(scratch / "scene.json", R"({
        "cloth": {"mesh": "panel.ply"},
        "pins": {"vertices": [20, 24]},
        "fps": 24, "frames": 4, "substeps": 20,
        "output": {"format": "ply", "point_cache": "mdd"}
    })");
    const CliResult r = run_cli("--json cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(r.out);
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
    ASSERT_EQ(stats.at("point_cache"), (scratch / "out" / "cloth.mdd").string());

    // Every frame: binary little-endian PLY with the input's quads, UVs and properties.
    const io::PolygonMesh input = io::read_ply_polygons(scratch / "panel.ply");
    const std::filesystem::path frames = scratch / "out" / "frames";
    std::vector<io::PolygonMesh> written;
    for (int f = 0; f <= 4; ++f) {
        const std::filesystem::path file = frames / ("frame_000" + std::to_string(f) + ".ply");
        EXPECT_EQ(read_text(file).rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
        written.push_back(io::read_ply_polygons(file));
        const io::PolygonMesh& m = written.back();
        EXPECT_EQ(m.face_starts, input.face_starts) << f;
        EXPECT_EQ(m.corner_vertices, input.corner_vertices) << f;
        EXPECT_EQ(m.uvs, input.uvs) << f;
        EXPECT_EQ(m.corner_uvs, input.corner_uvs) << f;
        ASSERT_EQ(m.vertex_attributes.size(), 1u);
        EXPECT_EQ(m.vertex_attributes[0].values, input.vertex_attributes[0].values);
        ASSERT_EQ(m.face_attributes.size(), 1u);
        EXPECT_EQ(m.face_attributes[0].name, "panel");
        EXPECT_EQ(m.face_attributes[0].values, input.face_attributes[0].values);
        EXPECT_EQ(m.normals.size(), input.positions.size());  // recomputed, written
    }
    EXPECT_EQ(written[0].positions, input.positions);
    EXPECT_LT(written[4].positions[0].z, 0.5 - 0.05);  // the free corner fell

    // cloth.mdd: 5 frames, times f / 24 s, each frame's positions as float.
    const std::string mdd = read_text(scratch / "out" / "cloth.mdd");
    const std::size_t points = (M + 1) * (M + 1);
    ASSERT_EQ(mdd.size(), 8 + 5 * 4 + 5 * points * 12);
    EXPECT_EQ(big_endian_word(mdd, 0), 5u);
    EXPECT_EQ(big_endian_word(mdd, 4), points);
    for (std::size_t f = 0; f < 5; ++f) {
        EXPECT_EQ(std::bit_cast<float>(big_endian_word(mdd, 8 + 4 * f)),
                  static_cast<float>(static_cast<double>(f) / 24.0));
        for (std::size_t v = 0; v < points; ++v) {
            const std::size_t at = 28 + 12 * (f * points + v);
            const Vec3d& p = written[f].positions[v];
            EXPECT_EQ(std::bit_cast<float>(big_endian_word(mdd, at)), static_cast<float>(p.x));
            EXPECT_EQ(std::bit_cast<float>(big_endian_word(mdd, at + 4)), static_cast<float>(p.y));
            EXPECT_EQ(std::bit_cast<float>(big_endian_word(mdd, at + 8)), static_cast<float>(p.z));
        }
    }

    // Interrupted after frame 2 and resumed on 2 threads: the same frames and cache, bitwise.
    const std::string scene = quoted(scratch / "scene.json");
    ASSERT_EQ(run_cli("cloth " + scene + " --no-preview --frames 2 --checkpoint-every 2 --out " +
                          quoted(scratch / "resumed"),
                      scratch)
                  .exit_code,
              0);
    const CliResult resumed =
        run_cli("cloth " + scene + " --no-preview --resume --threads 2 --out " +
                    quoted(scratch / "resumed"),
                scratch);
    ASSERT_EQ(resumed.exit_code, 0) << resumed.err;
    EXPECT_EQ(read_text(scratch / "resumed" / "frames" / "frame_0004.ply"),
              read_text(frames / "frame_0004.ply"));
    EXPECT_EQ(read_text(scratch / "resumed" / "cloth.mdd"), mdd);
}

}  // namespace
}  // namespace pliant::test
