// End-to-end tests of the pliant command line: exit codes and messages (0 ok, 1 bad input or I/O,
// 2 usage), and `pliant collide` against a brute-force enumeration of the feature pairs on small
// generated meshes written to OBJ/PLY files.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "integration/run_cli.hpp"
#include "pliant/collision/incidence.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/io/mesh_io.hpp"
#include "support/random_meshes.hpp"

namespace pliant::test {
namespace {

struct PairCounts {
    std::int64_t triangle_pairs = 0;
    std::int64_t vf_pairs = 0;
    std::int64_t ee_pairs = 0;
};

// O(n²) reference for the broad phase's contract: boxes span both ends of the step, grown by
// `inflation`; closed overlap; VF = vertex not in the face, EE = edges sharing no vertex,
// triangle pairs = triangles sharing no vertex.
PairCounts brute_force_counts(const geometry::TriangleMeshD& mesh,
                              std::span<const Vec3d> positions_t1, double inflation) {
    const std::size_t num_vertices = mesh.num_vertices();
    std::vector<AABBd> vertex_boxes(num_vertices);
    for (std::size_t v = 0; v < num_vertices; ++v) {
        vertex_boxes[v] =
            AABBd{min(mesh.positions[v], positions_t1[v]), max(mesh.positions[v], positions_t1[v])}
                .inflated(inflation);
    }
    const auto box_of = [&](std::span<const std::int32_t> corners) {
        AABBd box;
        for (const std::int32_t v : corners) {
            box.extend(vertex_boxes[static_cast<std::size_t>(v)]);
        }
        return box;
    };
    std::vector<AABBd> face_boxes;
    for (const geometry::Triangle& t : mesh.triangles) {
        face_boxes.push_back(box_of(t));
    }
    const geometry::MeshTopology topology = geometry::build_topology(mesh.triangles, num_vertices);
    std::vector<AABBd> edge_boxes;
    for (const geometry::Edge& e : topology.edges) {
        edge_boxes.push_back(box_of(e));
    }

    PairCounts counts;
    for (std::size_t a = 0; a < mesh.num_triangles(); ++a) {
        for (std::size_t b = a + 1; b < mesh.num_triangles(); ++b) {
            if (!collision::share_vertex(mesh.triangles[a], mesh.triangles[b]) &&
                overlaps(face_boxes[a], face_boxes[b])) {
                ++counts.triangle_pairs;
            }
        }
    }
    for (std::size_t v = 0; v < num_vertices; ++v) {
        for (std::size_t f = 0; f < mesh.num_triangles(); ++f) {
            if (!collision::contains_vertex(mesh.triangles[f], static_cast<std::int32_t>(v)) &&
                overlaps(vertex_boxes[v], face_boxes[f])) {
                ++counts.vf_pairs;
            }
        }
    }
    for (std::size_t a = 0; a < topology.num_edges(); ++a) {
        for (std::size_t b = a + 1; b < topology.num_edges(); ++b) {
            if (!collision::share_vertex(topology.edges[a], topology.edges[b]) &&
                overlaps(edge_boxes[a], edge_boxes[b])) {
                ++counts.ee_pairs;
            }
        }
    }
    return counts;
}

// A small accordion-folded sheet (layers 1.5 edge lengths apart): many near non-adjacent pairs,
// at the folds and between layers.
geometry::TriangleMesh folded_sheet() {
    constexpr int NX = 24;
    constexpr int NY = 16;
    constexpr float WIDTH = 1.0f;
    geometry::TriangleMesh mesh = geometry::make_grid_sheet(NX, NY, WIDTH, 0.6f);
    const float edge = WIDTH / NX;
    geometry::fold_accordion(mesh.positions, 6.0f * edge, 1.5f * edge);
    return mesh;
}

// The same mesh moved by a small smooth displacement (the end of a step).
geometry::TriangleMesh moved(geometry::TriangleMesh mesh, float amplitude) {
    for (Vec3f& p : mesh.positions) {
        p.z += amplitude * std::sin(7.0f * p.x + 3.0f * p.y);
        p.x += 0.5f * amplitude * std::cos(5.0f * p.y);
    }
    return mesh;
}

nlohmann::json parse_json(const CliResult& result) {
    EXPECT_EQ(result.exit_code, 0) << result.err;
    return nlohmann::json::parse(result.out);
}

void expect_counts(const nlohmann::json& json, const PairCounts& expected,
                   const geometry::TriangleMeshD& mesh) {
    EXPECT_EQ(json.at("triangles").get<std::int64_t>(),
              static_cast<std::int64_t>(mesh.num_triangles()));
    EXPECT_EQ(json.at("vertices").get<std::int64_t>(),
              static_cast<std::int64_t>(mesh.num_vertices()));
    EXPECT_EQ(json.at("triangle_pairs").get<std::int64_t>(), expected.triangle_pairs);
    EXPECT_EQ(json.at("vf_pairs").get<std::int64_t>(), expected.vf_pairs);
    EXPECT_EQ(json.at("ee_pairs").get<std::int64_t>(), expected.ee_pairs);
}

TEST(Cli, HelpExitsZero) {
    ScratchDir scratch;
    const CliResult r = run_cli("--help", scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("collide"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("demo"), std::string::npos) << r.out;
}

TEST(Cli, SubcommandHelpExitsZero) {
    ScratchDir scratch;
    const CliResult r = run_cli("collide --help", scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("--inflate"), std::string::npos) << r.out;
}

TEST(Cli, VersionPrintsNameAndVersion) {
    ScratchDir scratch;
    const CliResult r = run_cli("--version", scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("pliant " PLIANT_EXPECTED_VERSION), std::string::npos) << r.out;
}

TEST(Cli, UnknownOptionIsUsageError) {
    ScratchDir scratch;
    const CliResult r = run_cli("--no-such-option", scratch);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
}

TEST(Cli, MissingSubcommandIsUsageError) {
    ScratchDir scratch;
    const CliResult r = run_cli("", scratch);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
}

TEST(Cli, MistypedCommandSuggestsTheNearest) {
    ScratchDir scratch;
    const CliResult r = run_cli("colide mesh.obj", scratch);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("pliant: error: unknown command 'colide' (did you mean 'collide'?)"),
              std::string::npos)
        << r.err;
    const CliResult far = run_cli("--threads 2 frobnicate", scratch);
    EXPECT_EQ(far.exit_code, 2);
    EXPECT_NE(far.err.find("unknown command 'frobnicate'; the commands are: collide"),
              std::string::npos)
        << far.err;
    EXPECT_EQ(far.err.find("did you mean"), std::string::npos) << far.err;
}

TEST(Collide, AFileWithoutTrianglesIsAnError) {
    ScratchDir scratch;
    const auto empty = scratch / "empty.obj";
    std::ofstream(empty).flush();
    const CliResult r = run_cli("collide " + quoted(empty), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("expected a mesh with at least one triangle, got 0 vertices"),
              std::string::npos)
        << r.err;
    const auto binary = scratch / "random.obj";
    std::string bytes(4096, '\0');
    for (std::size_t k = 0; k < bytes.size(); ++k) {
        bytes[k] = static_cast<char>((k * 2654435761u) >> 13);
    }
    std::ofstream(binary, std::ios::binary) << bytes;
    const CliResult b = run_cli("collide " + quoted(binary), scratch);
    EXPECT_EQ(b.exit_code, 1);
    EXPECT_NE(b.err.find("not a text OBJ file"), std::string::npos) << b.err;
}

TEST(Collide, MissingFileNamesTheFile) {
    ScratchDir scratch;
    const auto missing = scratch / "no_such_mesh.ply";
    const CliResult r = run_cli("collide " + quoted(missing), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(missing.string()), std::string::npos) << r.err;
}

TEST(Collide, BrokenFileIsIoError) {
    ScratchDir scratch;
    const auto broken = scratch / "broken.ply";
    std::ofstream(broken)
        << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n";
    const CliResult r = run_cli("collide " + quoted(broken), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(broken.string()), std::string::npos) << r.err;
}

TEST(Collide, StaticMatchesBruteForce) {
    ScratchDir scratch;
    const auto path = scratch / "folded.ply";
    io::write_mesh(path, folded_sheet());
    const geometry::TriangleMeshD mesh = io::read_mesh(path);
    constexpr double INFLATION = 0.01;  // about a quarter edge
    const PairCounts expected = brute_force_counts(mesh, mesh.positions, INFLATION);
    ASSERT_GT(expected.vf_pairs, 0);
    ASSERT_GT(expected.ee_pairs, 0);

    const nlohmann::json json =
        parse_json(run_cli("collide " + quoted(path) + " --inflate 0.01 --json", scratch));
    expect_counts(json, expected, mesh);
    EXPECT_FALSE(json.at("swept").get<bool>());
    EXPECT_EQ(json.at("inflation").get<double>(), INFLATION);
    for (const char* key : {"edges", "build_ms", "refit_ms", "traverse_ms", "features_ms",
                            "total_ms", "threads", "memory_bytes"}) {
        EXPECT_TRUE(json.contains(key)) << key;
    }
}

TEST(Collide, SweptMatchesBruteForce) {
    ScratchDir scratch;
    const auto path_t0 = scratch / "frame_t0.ply";
    const auto path_t1 = scratch / "frame_t1.obj";
    const geometry::TriangleMesh sheet = folded_sheet();
    io::write_mesh(path_t0, sheet);
    io::write_mesh(path_t1, moved(sheet, 0.04f));  // about an edge: layers meet
    const geometry::TriangleMeshD mesh_t0 = io::read_mesh(path_t0);
    const geometry::TriangleMeshD mesh_t1 = io::read_mesh(path_t1);
    const PairCounts expected = brute_force_counts(mesh_t0, mesh_t1.positions, 0.0);
    const PairCounts static_counts = brute_force_counts(mesh_t0, mesh_t0.positions, 0.0);
    ASSERT_GT(expected.vf_pairs, static_counts.vf_pairs);

    const nlohmann::json json = parse_json(run_cli(
        "collide " + quoted(path_t0) + " --to " + quoted(path_t1) + " --repeat 3 --json", scratch));
    expect_counts(json, expected, mesh_t0);
    EXPECT_TRUE(json.at("swept").get<bool>());
}

TEST(Collide, CrumpledSheetMatchesBruteForceOnOneThread) {
    ScratchDir scratch;
    const auto path = scratch / "crumpled.obj";
    io::write_mesh(path, jittered_sheet(20, 20, 0.4f, 0.08f, 11));
    const geometry::TriangleMeshD mesh = io::read_mesh(path);
    const PairCounts expected = brute_force_counts(mesh, mesh.positions, 0.02);

    const nlohmann::json json = parse_json(
        run_cli("--threads 1 collide " + quoted(path) + " --inflate 0.02 --json", scratch));
    expect_counts(json, expected, mesh);
    EXPECT_EQ(json.at("threads").get<int>(), 1);
}

// Two squares crossing at right angles: square A in z = 0 split along y = x, square B in x = 0
// split along its diagonal through the origin. On the crossing segment (x = 0, z = 0,
// y in [-0.5, 0.5]) every triangle of A meets every triangle of B (the two pairs that only touch
// at the origin count too): 4 pairs. Moved apart by 5 m at t1: 0.
TEST(Collide, IntersectionsCountsCrossingSquares) {
    ScratchDir scratch;
    geometry::TriangleMeshD crossing;
    crossing.positions = {{-1, -1, 0},   {1, -1, 0},   {1, 1, 0},   {-1, 1, 0},
                          {0, -0.5, -1}, {0, 0.5, -1}, {0, 0.5, 1}, {0, -0.5, 1}};
    crossing.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    geometry::TriangleMeshD apart = crossing;
    for (std::size_t v = 4; v < 8; ++v) {
        apart.positions[v].x += 5.0;
    }
    const auto path_t0 = scratch / "crossing.obj";
    const auto path_t1 = scratch / "apart.ply";
    io::write_mesh(path_t0, crossing);
    io::write_mesh(path_t1, apart);
    const nlohmann::json json = parse_json(run_cli(
        "collide " + quoted(path_t0) + " --to " + quoted(path_t1) + " --intersections --json",
        scratch));
    EXPECT_EQ(json.at("intersecting_pairs").get<std::int64_t>(), 4);
    EXPECT_EQ(json.at("intersecting_pairs_t1").get<std::int64_t>(), 0);
    EXPECT_GE(json.at("intersections_ms").get<double>(), 0.0);
    const nlohmann::json plain =
        parse_json(run_cli("collide " + quoted(path_t0) + " --json", scratch));
    EXPECT_FALSE(plain.contains("intersecting_pairs"));
}

TEST(Collide, HumanSummary) {
    ScratchDir scratch;
    const auto path = scratch / "folded.ply";
    io::write_mesh(path, folded_sheet());
    const CliResult r = run_cli("collide " + quoted(path), scratch);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    for (const char* line :
         {"triangle pairs", "VF pairs", "EE pairs", "build", "refit", "traverse", "features"}) {
        EXPECT_NE(r.out.find(line), std::string::npos) << line << " in\n" << r.out;
    }
}

TEST(Collide, MismatchedFramesNameBothFilesAndCounts) {
    ScratchDir scratch;
    const auto path_t0 = scratch / "sheet_a.ply";
    const auto path_t1 = scratch / "sheet_b.ply";
    io::write_mesh(path_t0, geometry::make_grid_sheet(4, 4, 1.0f, 1.0f));  // 25 vertices
    io::write_mesh(path_t1, geometry::make_grid_sheet(5, 4, 1.0f, 1.0f));  // 30 vertices
    const CliResult r = run_cli("collide " + quoted(path_t0) + " --to " + quoted(path_t1), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(path_t0.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(path_t1.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("25"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("30"), std::string::npos) << r.err;
}

TEST(Collide, FramesWithDifferentTrianglesAreRejected) {
    ScratchDir scratch;
    const auto path_t0 = scratch / "sheet_a.ply";
    const auto path_t1 = scratch / "sheet_b.ply";
    geometry::TriangleMesh sheet = geometry::make_grid_sheet(4, 4, 1.0f, 1.0f);
    io::write_mesh(path_t0, sheet);
    std::swap(sheet.triangles[3][1], sheet.triangles[3][2]);
    io::write_mesh(path_t1, sheet);
    const CliResult r = run_cli("collide " + quoted(path_t0) + " --to " + quoted(path_t1), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("triangle 3"), std::string::npos) << r.err;
}

TEST(Collide, NegativeOrNanInflationIsUsageError) {
    ScratchDir scratch;
    const auto path = scratch / "sheet.ply";
    io::write_mesh(path, geometry::make_grid_sheet(2, 2, 1.0f, 1.0f));
    for (const char* value : {"-0.5", "nan", "inf", "abc"}) {
        const CliResult r = run_cli("collide " + quoted(path) + " --inflate=" + value, scratch);
        EXPECT_EQ(r.exit_code, 2) << value;
        EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("--inflate"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find(">= 0"), std::string::npos) << r.err;
    }
}

// Every bounded number option takes finite decimal numbers only: CLI11's own range check lets
// NaN through (pliant cloth --max-memory nan turned the memory check off) and reads 0x10 as 16.
TEST(Cli, BoundedNumberOptionsRefuseNanInfinityAndHex) {
    ScratchDir scratch;
    const std::string scene = quoted(scratch / "s.json");
    std::ofstream(scratch / "s.json") << R"({"cloth": {"grid": {"quads": [2, 2]}}, "frames": 1})";
    for (const char* value : {"nan", "-nan", "inf", "0x10", "1e400", "0"}) {
        const CliResult r = run_cli(
            "cloth " + scene + " --out " + quoted(scratch / "out") + " --max-memory " + value,
            scratch);
        EXPECT_EQ(r.exit_code, 2) << value;
        EXPECT_NE(r.err.find("--max-memory: must be a finite number in [1, "), std::string::npos)
            << r.err;
        EXPECT_FALSE(std::filesystem::exists(scratch / "out")) << value;
    }
    const CliResult camera = run_cli("render in.nrrd -o out.png --camera 30,nan,0", scratch);
    EXPECT_EQ(camera.exit_code, 2);
    EXPECT_NE(camera.err.find("--camera: must be a finite number"), std::string::npos)
        << camera.err;
    const CliResult fov = run_cli("dataset in.nrrd --out d --fov inf", scratch);
    EXPECT_EQ(fov.exit_code, 2);
    EXPECT_NE(fov.err.find("--fov: must be a finite number in [1, 170]"), std::string::npos)
        << fov.err;
}

TEST(Collide, ZeroRepeatIsUsageError) {
    ScratchDir scratch;
    const auto path = scratch / "sheet.ply";
    io::write_mesh(path, geometry::make_grid_sheet(2, 2, 1.0f, 1.0f));
    const CliResult r = run_cli("collide " + quoted(path) + " --repeat 0", scratch);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("--repeat"), std::string::npos) << r.err;
}

TEST(Collide, UnsupportedExtensionIsIoError) {
    ScratchDir scratch;
    const auto path = scratch / "mesh.stl";
    std::ofstream(path) << "solid x\nendsolid x\n";
    const CliResult r = run_cli("collide " + quoted(path), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(".stl"), std::string::npos) << r.err;
}

// The paper's table on small rows: pliant's pairs equal the brute force's (and Embree's, when
// built with it); the 2,244 row carries the paper's numbers.
TEST(BenchCommand, BvhTableAgreesWithTheBruteForce) {
    ScratchDir scratch;
    const nlohmann::json table =
        parse_json(run_cli("--json bench bvh --sizes 2244,800 --repeat 1", scratch));
    EXPECT_TRUE(table.at("ok").get<bool>());
    ASSERT_EQ(table.at("rows").size(), 2u);
    for (const nlohmann::json& row : table.at("rows")) {
        const std::int64_t pairs = row.at("pliant").at("pairs").get<std::int64_t>();
        EXPECT_GT(pairs, 0);
        EXPECT_EQ(row.at("brute_force").at("pairs").get<std::int64_t>(), pairs);
        if (!row.at("embree").is_null()) {
            EXPECT_EQ(row.at("embree").at("pairs").get<std::int64_t>(), pairs);
        }
    }
    EXPECT_EQ(table.at("rows")[0].at("paper").at("triangles"), 2244);
    EXPECT_TRUE(table.at("rows")[1].at("paper").is_null());
    const CliResult bad = run_cli("bench bvh --repeat 0", scratch);
    EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

TEST(Demo, WritesOutputsThatCollideReproduces) {
    ScratchDir scratch;
    const auto dir = scratch / "demo";
    const nlohmann::json summary = parse_json(run_cli(
        "--json demo --cloth-frames 2 --deform-frames 3 --nerf-iterations 200 --nerf-resolution 64 "
        "--nerf-views 20 --out " +
            quoted(dir),
        scratch));
    ASSERT_TRUE(std::filesystem::exists(dir / "folded_sheet.ply"));
    ASSERT_TRUE(std::filesystem::exists(dir / "folded_sheet_t1.ply"));
    ASSERT_TRUE(std::filesystem::exists(dir / "summary.json"));
    EXPECT_EQ(nlohmann::json::parse(read_text(dir / "summary.json")), summary);
    EXPECT_EQ(summary.at("sheet").at("triangles").get<std::int64_t>(), 35912);
    EXPECT_EQ(summary.at("bvh_table").at("rows").size(), 3u);
    EXPECT_EQ(summary.at("drape").at("frames"), 2);
    EXPECT_EQ(summary.at("drape").at("triangles"), 35912);
    EXPECT_TRUE(std::filesystem::exists(dir / "drape" / "frames" / "frame_0002.obj"));
    EXPECT_TRUE(std::filesystem::exists(dir / "drape" / "stats.json"));
    EXPECT_EQ(summary.at("drape").at("max_intersecting_pairs"), 0);
    EXPECT_TRUE(std::filesystem::exists(summary.at("drape").at("preview").get<std::string>()));
    // The volume: a PNG and a turntable (MP4, or PNG frames without ffmpeg).
    const nlohmann::json& volume = summary.at("volume");
    EXPECT_TRUE(std::filesystem::exists(volume.at("png").get<std::string>()));
    EXPECT_GT(volume.at("png_ms").get<double>(), 0.0);
    EXPECT_FALSE(volume.at("source").get<std::string>().empty());
    // The deformed volume and the pipeline from images: dataset, reconstruction (scored on the
    // held-out views, which no training step saw), cleaning, deformation.
    EXPECT_EQ(summary.at("deform").at("frames"), 3);
    EXPECT_EQ(summary.at("deform").at("inverted_tets"), 0);
    const nlohmann::json& nerf = summary.at("nerf");
    EXPECT_EQ(nerf.at("dataset").at("train"), 18);
    EXPECT_EQ(nerf.at("dataset").at("test"), 2);
    EXPECT_TRUE(std::filesystem::exists(dir / "nerf" / "dataset" / "transforms_train.json"));
    EXPECT_TRUE(std::filesystem::exists(nerf.at("train").at("output").get<std::string>()));
    EXPECT_TRUE(std::filesystem::exists(nerf.at("cleaned").get<std::string>()));
    EXPECT_TRUE(std::filesystem::exists(nerf.at("compare_png").get<std::string>()));
    EXPECT_GT(nerf.at("train").at("iterations").get<std::int64_t>(), 0);
    // 200 iterations (a few seconds) already reproduce the held-out views far better than an
    // empty volume would (11.6 dB on these two views: black against the images).
    EXPECT_EQ(nerf.at("train").at("iterations"), 200);
    EXPECT_GT(nerf.at("held_out_psnr").get<double>(), 20.0);
    EXPECT_EQ(nerf.at("deform").at("frames"), 3);
    EXPECT_EQ(nerf.at("deform").at("inverted_tets"), 0);
    for (const char* scene : {"drape", "twist", "pile", "flag"}) {
        const nlohmann::json& s = summary.at("cloth").at(scene);
        EXPECT_EQ(s.at("frames"), 2) << scene;
        EXPECT_EQ(s.at("max_intersecting_pairs"), 0) << scene;
        EXPECT_TRUE(std::filesystem::exists(dir / scene / "stats.json")) << scene;
    }
    // Untangling: the drape without self-collision falls through itself; the untangled run
    // starts from its last frame, intersection-free, and `pliant cloth` on the written scene
    // file reproduces it.
    const nlohmann::json& untangle = summary.at("untangle");
    EXPECT_TRUE(std::filesystem::exists(untangle.at("fall_scene").get<std::string>()));
    EXPECT_GT(untangle.at("fall_intersecting_pairs").get<std::int64_t>(), 0);
    EXPECT_EQ(untangle.at("initial_intersecting_pairs"), untangle.at("fall_intersecting_pairs"));
    EXPECT_EQ(untangle.at("untangle").at("pairs_left"), 0);
    EXPECT_EQ(untangle.at("max_intersecting_pairs"), 0);
    EXPECT_EQ(untangle.at("frames"), 2);
    EXPECT_TRUE(std::filesystem::exists(dir / "untangle" / "frames" / "frame_0002.obj"));
    // Two sheets crossing like an X: untangled by a region move, apart in every frame.
    const nlohmann::json& crossing = untangle.at("crossing");
    EXPECT_GT(crossing.at("initial_intersecting_pairs").get<std::int64_t>(), 40);
    EXPECT_EQ(crossing.at("untangle").at("pairs_left"), 0);
    EXPECT_GE(crossing.at("untangle").at("region_moves").get<int>(), 1);
    EXPECT_EQ(crossing.at("max_intersecting_pairs"), 0);
    EXPECT_TRUE(
        std::filesystem::exists(dir / "untangle" / "crossing" / "frames" / "frame_0002.obj"));
    const nlohmann::json again = parse_json(run_cli(
        "--json cloth " + quoted(std::filesystem::path(untangle.at("scene").get<std::string>())) +
            " --out " + quoted(scratch / "untangle_again") + " --no-preview",
        scratch));
    for (const char* key : {"iterations", "pairs_left", "max_displacement_m"}) {
        EXPECT_EQ(again.at("untangle").at(key), untangle.at("untangle").at(key)) << key;
    }
    EXPECT_EQ(read_text(scratch / "untangle_again" / "frames" / "frame_0002.obj"),
              read_text(dir / "untangle" / "frames" / "frame_0002.obj"));

    // The written files and the printed inflation give the demo's counts exactly.
    for (const char* mode : {"static", "swept"}) {
        const nlohmann::json& expected = summary.at(mode);
        std::string args = "collide " + quoted(dir / "folded_sheet.ply");
        const bool swept = expected.at("swept").get<bool>();
        if (swept) {
            args += " --to " + quoted(dir / "folded_sheet_t1.ply") + " --ccd";
        }
        args += " --inflate " + expected.at("inflation").dump() + " --json";
        const nlohmann::json json = parse_json(run_cli(args, scratch));
        for (const char* key : {"triangle_pairs", "vf_pairs", "ee_pairs"}) {
            EXPECT_EQ(json.at(key), expected.at(key)) << mode << " " << key;
        }
        EXPECT_EQ(expected.contains("vf_hits"), swept) << mode;
        if (swept) {
            // The layers are 1.5 edges apart and move by 0.1 edge: nothing touches.
            for (const char* key : {"vf_hits", "ee_hits", "earliest_toi"}) {
                EXPECT_EQ(json.at(key), expected.at(key)) << mode << " " << key;
            }
            EXPECT_EQ(expected.at("vf_hits").get<std::int64_t>(), 0);
            EXPECT_EQ(expected.at("ee_hits").get<std::int64_t>(), 0);
        }
        EXPECT_GT(expected.at("vf_pairs").get<std::int64_t>(), 0) << mode;
    }
}

}  // namespace
}  // namespace pliant::test
