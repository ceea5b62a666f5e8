// `pliant cloth` end to end: frames and stats written, the physics visible in the frames, bad
// scenes rejected with the key named and nothing written.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "integration/run_cli.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/geometry/generate.hpp"
#include "pliant/io/mesh_io.hpp"
#include "pliant/io/png.hpp"
#include "pliant/io/video.hpp"
#include "pliant/render/image.hpp"

namespace pliant::test {
namespace {

void write(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path) << text;
}

// Writes `scene` to scratch/NAME.json and runs `pliant cloth` on it into scratch/NAME.
CliResult run_scene(const ScratchDir& scratch, const std::string& name, const std::string& scene,
                    const std::string& options = " --no-preview") {
    write(scratch / (name + ".json"), scene);
    return run_cli("cloth " + quoted(scratch / (name + ".json")) + " --out " +
                       quoted(scratch / name) + options,
                   scratch);
}

TEST(ClothCommand, DropsASheetOnASphereAndWritesFramesAndStats) {
    ScratchDir scratch;
    write(scratch / "scene.json", R"({
        "cloth": {"grid": {"size": [1.0, 1.0], "quads": [12, 12]}, "translate": [0, 0, 0.6]},
        "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.3}}],
        "fps": 24, "frames": 30, "substeps": 10
    })");
    const CliResult r = run_cli(
        "--json cloth " + quoted(scratch / "scene.json") + " --out " + quoted(scratch / "out"),
        scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(r.out);
    EXPECT_EQ(stats.at("triangles"), 288);
    // 12 × 12 quads: 12 · 13 · 2 + 144 edges, of which 2 · 12 · 11 + 144 interior (hinges); the
    // default bending model is dihedral.
    EXPECT_EQ(stats.at("bending_constraints"), 408);
    EXPECT_EQ(stats.at("isometric_bending_constraints"), 0);
    EXPECT_EQ(stats.at("frames").size(), 30u);
    EXPECT_FALSE(stats.at("interrupted").get<bool>());
    EXPECT_EQ(nlohmann::json::parse(read_text(scratch / "out" / "stats.json")), stats);
    EXPECT_GT(stats.at("frames").back().at("obstacle_contacts").get<int>(), 0);
    // Frame 0 is the input; frame 30 rests on the sphere, thickness away from it.
    const geometry::TriangleMeshD first =
        io::read_mesh(scratch / "out" / "frames" / "frame_0000.obj");
    const geometry::TriangleMeshD last =
        io::read_mesh(scratch / "out" / "frames" / "frame_0030.obj");
    ASSERT_EQ(first.positions.size(), 169u);
    EXPECT_DOUBLE_EQ(first.positions[84].z, 0.6);
    EXPECT_NEAR(last.positions[84].z, 0.305, 0.005);  // the centre vertex
    for (const Vec3d& p : last.positions) {
        EXPECT_GE(norm(p), 0.3 + 0.005 * 0.99);
    }
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
    EXPECT_EQ(stats.at("initial_intersecting_pairs"), 0);
    for (const char* key : {"step_ms", "refit_ms", "traverse_ms", "narrow_ms", "response_ms",
                            "contacts", "ccd_hits", "intersecting_pairs", "strain_p90",
                            "strain_p99", "strain_max", "edges_over_10_percent"}) {
        EXPECT_TRUE(stats.at("frames").back().contains(key)) << key;
    }
    // Edge strain of the written last frame, recomputed here from the two files: the stats
    // report it (to the precision the OBJ keeps), and the resting sheet is within 10 % of its rest
    // lengths (it stretches more at the impact: 20 % at most, at 10 substeps).
    double last_strain = 0.0;
    for (const geometry::Triangle& t : first.triangles) {
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(t[static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)]);
            last_strain =
                std::max(last_strain, norm(last.positions[a] - last.positions[b]) /
                                              norm(first.positions[a] - first.positions[b]) -
                                          1.0);
        }
    }
    EXPECT_NEAR(stats.at("frames").back().at("strain_max").get<double>(), last_strain, 1e-5);
    EXPECT_LT(last_strain, 0.1);
    EXPECT_LT(stats.at("max_strain").get<double>(), 0.3);
    EXPECT_GE(stats.at("max_strain").get<double>(), stats.at("max_strain_p99").get<double>());
    // The preview: an MP4 of 31 frames (ffmpeg is a dependency; PNG frames without it).
    ASSERT_TRUE(stats.contains("preview"));
    const std::filesystem::path preview = stats.at("preview").get<std::string>();
    if (preview.extension() == ".mp4") {
        EXPECT_GT(std::filesystem::file_size(preview), 1000u);
    } else {
        EXPECT_TRUE(std::filesystem::exists(preview / "frame_0030.png"));
    }
    // --frames overrides the scene; --no-preview writes none.
    const CliResult short_run = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                            quoted(scratch / "short") + " --frames 2 --no-preview",
                                        scratch);
    ASSERT_EQ(short_run.exit_code, 0) << short_run.err;
    EXPECT_TRUE(std::filesystem::exists(scratch / "short" / "frames" / "frame_0002.obj"));
    EXPECT_FALSE(std::filesystem::exists(scratch / "short" / "frames" / "frame_0003.obj"));
    EXPECT_FALSE(std::filesystem::exists(scratch / "short" / "preview.mp4"));
    EXPECT_FALSE(std::filesystem::exists(scratch / "short" / "preview"));
}

// --preview-size takes WxH, as --size does everywhere else; the old "W H" form is a usage error.
TEST(ClothCommand, PreviewSizeIsWxH) {
    ScratchDir scratch;
    write(scratch / "scene.json", R"({"cloth": {"grid": {"size": [1, 1], "quads": [4, 4]}},
        "frames": 1, "substeps": 2})");
    for (const char* size : {"64 48", "8x8", "64x"}) {
        const CliResult r = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                        quoted(scratch / "out") + " --preview-size " + size,
                                    scratch);
        EXPECT_EQ(r.exit_code, 2) << size << ": " << r.err;
        // "64 48": CLI11 names the stray "48"; the malformed sizes name the option.
        EXPECT_NE(r.err.find(std::string(size) == "64 48" ? "not expected: 48" : "--preview-size"),
                  std::string::npos)
            << r.err;
    }
}

// Without ffmpeg on the PATH the preview is PNG frames of the requested size.
TEST(ClothCommand, PreviewFallsBackToPngFramesWithoutFfmpeg) {
    ScratchDir scratch;
    write(scratch / "scene.json", R"({
        "cloth": {"grid": {"size": [1.0, 1.0], "quads": [6, 6]}, "translate": [0, 0, 0.5]},
        "obstacles": [{"sphere": {"radius": 0.3}}, {"plane": {"point": [0, 0, -0.3]}}],
        "frames": 3, "substeps": 5
    })");
    const CliResult r = run_cli("--json cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --preview-size 64x48",
                                scratch, "PATH=/nonexistent");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(r.out);
    EXPECT_EQ(stats.at("preview"), (scratch / "out" / "preview").string());
    EXPECT_FALSE(std::filesystem::exists(scratch / "out" / "preview.mp4"));
    for (int frame = 0; frame <= 3; ++frame) {
        const render::Image image = io::read_png(scratch / "out" / "preview" /
                                                 ("frame_000" + std::to_string(frame) + ".png"));
        EXPECT_EQ(image.width, 64);
        EXPECT_EQ(image.height, 48);
        // Not blank: the cloth's red is in the picture.
        bool has_red = false;
        for (int y = 0; y < image.height && !has_red; ++y) {
            for (int x = 0; x < image.width; ++x) {
                const render::Rgb8 c = image.at(x, y);
                has_red |= c.r > 150 && c.g < 120 && c.b < 120;
            }
        }
        EXPECT_TRUE(has_red) << "frame " << frame;
    }
}

// Ctrl-C (SIGINT) during a long run: it stops after the frame in progress, keeps the frames,
// finishes the preview, writes stats.json (interrupted: true), says where they are, exits 130.
TEST(ClothCommand, InterruptKeepsWhatWasWritten) {
    ScratchDir scratch;
    write(scratch / "long.json", R"({
        "cloth": {"grid": {"size": [1.0, 1.0], "quads": [10, 10]}, "translate": [0, 0, 1]},
        "frames": 1000000, "substeps": 2
    })");
    const std::filesystem::path out = scratch / "out";
    const std::string command =
        quoted(PLIANT_CLI) + " cloth " + quoted(scratch / "long.json") + " --out " + quoted(out) +
        " 2>" + quoted(scratch / "err.txt") + " & pid=$!; while [ ! -f " +
        quoted(out / "frames" / "frame_0003.obj") + " ]; do sleep 0.02; done; kill -INT $pid; " +
        "wait $pid; echo $? >" + quoted(scratch / "code.txt");
    ASSERT_EQ(std::system(command.c_str()), 0);
    EXPECT_EQ(read_text(scratch / "code.txt"), "130\n");
    const std::string err = read_text(scratch / "err.txt");
    EXPECT_NE(err.find("pliant: interrupted: stopped after frame"), std::string::npos) << err;
    EXPECT_NE(err.find((out / "frames").string()), std::string::npos) << err;
    const nlohmann::json stats = nlohmann::json::parse(read_text(out / "stats.json"));
    EXPECT_TRUE(stats.at("interrupted").get<bool>());
    const auto done = stats.at("frames").size();
    EXPECT_GE(done, 3u);
    EXPECT_TRUE(std::filesystem::exists(out / "frames" / fmt::format("frame_{:04d}.obj", done)));
    EXPECT_FALSE(
        std::filesystem::exists(out / "frames" / fmt::format("frame_{:04d}.obj", done + 1)));
    ASSERT_TRUE(stats.contains("preview"));
    EXPECT_TRUE(std::filesystem::exists(stats.at("preview").get<std::string>()));
}

// Every built-in scene runs (two frames, no preview) without intersections.
TEST(ClothCommand, BuiltInScenesRun) {
    ScratchDir scratch;
    for (const char* name : {"drape", "twist", "pile", "flag"}) {
        const std::filesystem::path scene =
            std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / (std::string(name) + ".json");
        const CliResult r = run_cli("--json cloth " + quoted(scene) + " --out " +
                                        quoted(scratch / name) + " --frames 2 --no-preview",
                                    scratch);
        ASSERT_EQ(r.exit_code, 0) << name << ": " << r.err;
        const nlohmann::json stats = nlohmann::json::parse(r.out);
        EXPECT_EQ(stats.at("max_intersecting_pairs"), 0) << name;
        EXPECT_EQ(stats.at("frames").size(), 2u) << name;
    }
}

// A mesh obstacle from an OBJ file (a box, moving sideways) holds and carries the cloth.
TEST(ClothCommand, MeshObstacleFromAFile) {
    ScratchDir scratch;
    write(scratch / "table.obj", R"(v -0.5 -0.5 -0.2
v 0.5 -0.5 -0.2
v 0.5 0.5 -0.2
v -0.5 0.5 -0.2
v -0.5 -0.5 0
v 0.5 -0.5 0
v 0.5 0.5 0
v -0.5 0.5 0
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
)");
    write(scratch / "scene.json", R"({
        "cloth": {"grid": {"size": [0.4, 0.4], "quads": [8, 8]}, "translate": [0, 0, 0.02]},
        "obstacles": [{"mesh": {"file": "table.obj"},
                       "motion": {"keyframes": [{"time": 0},
                                                {"time": 1, "translate": [0.2, 0, 0]}]}}],
        "material": {"static_friction": 0.6, "kinetic_friction": 0.6},
        "frames": 24, "substeps": 10
    })");
    const CliResult r = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const geometry::TriangleMeshD last =
        io::read_mesh(scratch / "out" / "frames" / "frame_0024.obj");
    double mean_x = 0.0;
    for (const Vec3d& p : last.positions) {
        EXPECT_GT(p.z, 0.004);  // on the table, thickness above it
        mean_x += p.x;
    }
    EXPECT_NEAR(mean_x / static_cast<double>(last.positions.size()), 0.2, 0.03);
    EXPECT_EQ(r.err.find("wound inward"), std::string::npos) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / "out" / "stats.json"));
    EXPECT_EQ(stats.at("max_obstacle_intersections"), 0);

    // The same table wound inward (every face reversed) holds cloth inside it, as a container:
    // the command says so.
    std::ifstream table(scratch / "table.obj");
    std::string inward;
    for (std::string line; std::getline(table, line);) {
        std::istringstream fields(line);
        std::string kind, a, b, c;
        fields >> kind >> a >> b >> c;
        inward += kind == "f" ? fmt::format("f {} {} {}\n", a, c, b) : line + "\n";
    }
    write(scratch / "table.obj", inward);
    const CliResult turned = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                         quoted(scratch / "out") + " --no-preview --frames 1",
                                     scratch);
    EXPECT_EQ(turned.exit_code, 0) << turned.err;
    EXPECT_NE(turned.err.find("obstacles[0].mesh.file"), std::string::npos) << turned.err;
    EXPECT_NE(turned.err.find("a closed mesh wound inward"), std::string::npos) << turned.err;
}

// Cloth given behind a plane (its normal flipped by mistake) is named in a warning, comes out
// onto the plane and falls from there: not thrown (it flew off at 288 m/s, 23.6 m in 2 frames).
TEST(ClothCommand, ClothGivenInsideAnObstacleIsReportedAndComesOut) {
    ScratchDir scratch;
    write(scratch / "scene.json", R"({
        "cloth": {"grid": {"size": [1, 1], "quads": [8, 8]}, "translate": [0, 0, 0.3]},
        "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, -1]}}],
        "frames": 4
    })");
    const CliResult r = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("81 of the cloth's 81 vertices start inside an obstacle (the deepest "
                         "0.3 m in)"),
              std::string::npos)
        << r.err;
    // Every triangle is behind the plane in the first frames, none at the last.
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / "out" / "stats.json"));
    EXPECT_EQ(stats.at("frames").front().at("obstacle_intersections"), 128);
    EXPECT_EQ(stats.at("frames").back().at("obstacle_intersections"), 0);
    EXPECT_EQ(stats.at("max_obstacle_intersections"), 128);
    const geometry::TriangleMeshD last =
        io::read_mesh(scratch / "out" / "frames" / "frame_0004.obj");
    for (const Vec3d& p : last.positions) {
        // Under the plane (pushed out at most half the thickness per substep: 0.3 m in 120
        // substeps, 3 frames), fallen for 4 frames at most (0.5 g t² = 0.137 m).
        EXPECT_LT(p.z, -0.005);
        EXPECT_GT(p.z, -0.005 - 0.137);
    }
}

// A thin blade (one triangle of a mesh obstacle) through a pinned sheet, between its vertices: no
// vertex is inside or near it, and the frames count where it passes through the cloth.
TEST(ClothCommand, AThinObstacleThroughTheClothIsCounted) {
    ScratchDir scratch;
    write(scratch / "blade.obj", R"(v 0.05 -0.1 -0.1
v 0.05 0.1 -0.1
v 0.05 0 0.1
f 1 2 3
)");
    std::string pins;
    for (int v = 0; v < 25; ++v) {
        pins += (v > 0 ? ", " : "") + std::to_string(v);
    }
    const CliResult r = run_scene(scratch, "blade", R"({
        "cloth": {"grid": {"size": [0.4, 0.4], "quads": [4, 4]}},
        "pins": {"vertices": [)" + pins + R"(]},
        "obstacles": [{"mesh": {"file": "blade.obj"}}],
        "frames": 3, "substeps": 4
    })");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / "blade" / "stats.json"));
    // The blade's cross-section with the sheet (x = 0.05, |y| ≤ 0.05) lies in the triangles
    // between x = 0 and 0.1; the reference counts them on the written frame.
    const geometry::TriangleMeshD cloth =
        io::read_mesh(scratch / "blade" / "frames" / "frame_0003.obj");
    const geometry::TriangleMeshD blade = io::read_mesh(scratch / "blade.obj");
    const std::int64_t expected = collision::count_intersecting_pairs(
        cloth.positions, cloth.triangles, blade.positions, blade.triangles);
    EXPECT_GE(expected, 2);
    for (const nlohmann::json& frame : stats.at("frames")) {
        EXPECT_EQ(frame.at("obstacle_intersections"), expected) << frame.at("frame");
    }
    EXPECT_EQ(stats.at("max_obstacle_intersections"), expected);
    EXPECT_NE(r.out.find(fmt::format("and {} obstacle intersections", expected)), std::string::npos)
        << r.out;
}

// A seam left unwelded in the file (two squares whose shared edge has its own vertices in each)
// is named in a warning: the cloth is cut there.
TEST(ClothCommand, UnweldedSeamsAreNamed) {
    ScratchDir scratch;
    write(scratch / "seam.obj", R"(v 0 0 0.3
v 0.1 0 0.3
v 0.1 0.1 0.3
v 0 0.1 0.3
v 0.1 0 0.3
v 0.2 0 0.3
v 0.2 0.1 0.3
v 0.1 0.1 0.3
f 1 2 3
f 1 3 4
f 5 6 7
f 5 7 8
)");
    write(scratch / "scene.json", R"({"cloth": {"mesh": "seam.obj"}, "frames": 1})");
    const CliResult r = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("2 of the cloth's 8 vertices lie exactly on another vertex"),
              std::string::npos)
        << r.err;
}

// Legal but almost certainly not meant: a mesh with an edge of three triangles, and a pin region
// that holds no vertex, are named in warnings; the run goes on.
TEST(ClothCommand, NonManifoldMeshesAndEmptyPinRegionsAreWarnedAbout) {
    ScratchDir scratch;
    write(scratch / "fin.obj",
          "v 0 0 0.3\nv 0.1 0 0.3\nv 0 0.1 0.3\nv 0 0 0.4\nv 0 -0.1 0.3\n"
          "f 1 2 3\nf 1 2 4\nf 1 2 5\n");
    write(scratch / "scene.json", R"({"cloth": {"mesh": "fin.obj"},
        "pins": [{"regions": [{"min": [5, 5, 5], "max": [6, 6, 6]}]}], "frames": 1})");
    const CliResult r = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("1 of its 7 edges are shared by more than two triangles (non-manifold)"),
              std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find("pins[0] region 0 (min (5, 5, 5), max (6, 6, 6)) holds none of the "
                         "cloth's 5 vertices"),
              std::string::npos)
        << r.err;
}

// A sheet with a dent pushed through another sheet below it (one mesh) is untangled before the
// first frame and stays apart; with "untangle": false it is only reported.
TEST(ClothCommand, ClothThatStartsIntersectingIsUntangled) {
    ScratchDir scratch;
    const geometry::TriangleMeshD lower =
        geometry::convert_precision<double>(geometry::make_grid_sheet(12, 12, 1.0f, 1.0f));
    geometry::TriangleMeshD mesh = lower;
    const auto offset = static_cast<std::int32_t>(lower.positions.size());
    for (Vec3d p : lower.positions) {
        const double r = std::sqrt(p.x * p.x + p.y * p.y);
        p.z = 0.02 - (r < 0.3 ? 0.03 * (1.0 + std::cos(M_PI * r / 0.3)) : 0.0);
        mesh.positions.push_back(p);
    }
    for (const geometry::Triangle& t : lower.triangles) {
        mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
    }
    io::write_mesh(scratch / "dent.obj", mesh);
    for (const bool untangle : {true, false}) {
        write(scratch / "dent.json",
              fmt::format(R"({{"cloth": {{"mesh": "dent.obj"}}, "frames": 3, "substeps": 10,
                  "gravity": [0, 0, 0], "untangle": {}}})",
                          untangle));
        const std::filesystem::path out = scratch / (untangle ? "untangled" : "reported");
        const CliResult run = run_cli("--json cloth " + quoted(scratch / "dent.json") + " --out " +
                                          quoted(out) + " --no-preview",
                                      scratch);
        ASSERT_EQ(run.exit_code, 0) << run.err;
        EXPECT_NE(run.err.find("intersects itself at the start"), std::string::npos) << run.err;
        const nlohmann::json stats = nlohmann::json::parse(run.out);
        EXPECT_GT(stats.at("initial_intersecting_pairs").get<int>(), 10);
        if (untangle) {
            EXPECT_NE(run.err.find("untangled in"), std::string::npos) << run.err;
            EXPECT_EQ(stats.at("untangle").at("pairs_left"), 0);
            EXPECT_EQ(stats.at("untangle").at("region_moves"), 0);  // a closed contour
            EXPECT_LT(stats.at("untangle").at("max_displacement_m").get<double>(), 0.1);
            EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
            // The first frame written is the untangled state.
            const geometry::TriangleMeshD first = io::read_mesh(out / "frames" / "frame_0000.obj");
            EXPECT_EQ(collision::count_intersecting_pairs(first.positions, first.triangles), 0);
        } else {
            EXPECT_TRUE(stats.at("untangle").is_null());
            EXPECT_GT(stats.at("max_intersecting_pairs").get<int>(), 0);
        }
    }
}

// Robustness: a cloth that intersects itself at the start is reported and simulated without
// getting worse; everything pinned stays put; a 100-second step stays finite; zero-area
// triangles are data; NaN in the input is an error naming it.
TEST(ClothCommand, HostileInputsAreReportedOrSurvived) {
    ScratchDir scratch;
    // Two squares crossing at right angles: 4 intersecting pairs.
    write(scratch / "crossing.obj", R"(v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
v 0 -0.5 -1
v 0 0.5 -1
v 0 0.5 1
v 0 -0.5 1
f 1 2 3
f 1 3 4
f 5 6 7
f 5 7 8
)");
    write(scratch / "crossing.json",
          R"({"cloth": {"mesh": "crossing.obj"}, "frames": 4, "substeps": 5})");
    const CliResult crossing =
        run_cli("--json cloth " + quoted(scratch / "crossing.json") + " --out " +
                    quoted(scratch / "crossing") + " --no-preview",
                scratch);
    ASSERT_EQ(crossing.exit_code, 0) << crossing.err;
    EXPECT_NE(crossing.err.find("intersects itself at the start"), std::string::npos)
        << crossing.err;
    const nlohmann::json stats = nlohmann::json::parse(crossing.out);
    EXPECT_EQ(stats.at("initial_intersecting_pairs"), 4);
    EXPECT_LE(stats.at("max_intersecting_pairs").get<int>(), 4);
    // Crossing from edge to edge: untangling is tried and its result reported.
    EXPECT_LE(stats.at("untangle").at("pairs_left").get<int>(), 4);
    EXPECT_GT(stats.at("untangle").at("iterations").get<int>(), 0);

    // Everything pinned, one 100 s frame: nothing moves.
    write(scratch / "pinned.json", R"({"cloth": {"grid": {"size": [1, 1], "quads": [4, 4]}},
        "pins": {"regions": [{"min": [-1, -1, -1], "max": [1, 1, 1]}]},
        "fps": 0.01, "frames": 2, "substeps": 1})");
    const CliResult pinned = run_cli("cloth " + quoted(scratch / "pinned.json") + " --out " +
                                         quoted(scratch / "pinned") + " --no-preview",
                                     scratch);
    ASSERT_EQ(pinned.exit_code, 0) << pinned.err;
    EXPECT_EQ(read_text(scratch / "pinned" / "frames" / "frame_0000.obj"),
              read_text(scratch / "pinned" / "frames" / "frame_0002.obj"));

    // Huge steps onto a sphere, a zero-area triangle in the mesh: finite output.
    write(scratch / "sliver.obj", R"(v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
v 0.5 0 1
f 1 2 3
f 1 3 4
f 1 5 2
)");
    // With either stretch solver (chains: the sliver's collinear edges form one chain).
    for (const std::string solver : {"edges", "chains"}) {
        write(scratch / "huge.json", R"({"cloth": {"mesh": "sliver.obj"},
            "obstacles": [{"sphere": {"center": [0.5, 0.5, 0], "radius": 0.5}}],
            "material": {"stretch_solver": ")" +
                                         solver + R"("},
            "fps": 0.1, "frames": 3, "substeps": 1})");
        const CliResult huge = run_cli("cloth " + quoted(scratch / "huge.json") + " --out " +
                                           quoted(scratch / ("huge_" + solver)) + " --no-preview",
                                       scratch);
        ASSERT_EQ(huge.exit_code, 0) << solver << ": " << huge.err;
        const geometry::TriangleMeshD last =
            io::read_mesh(scratch / ("huge_" + solver) / "frames" / "frame_0003.obj");
        for (const Vec3d& p : last.positions) {
            EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) << solver;
        }
    }

    write(scratch / "nan.obj", "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n");
    write(scratch / "nan.json", R"({"cloth": {"mesh": "nan.obj"}})");
    const CliResult nan = run_cli("cloth " + quoted(scratch / "nan.json") + " --out " +
                                      quoted(scratch / "nan") + " --no-preview",
                                  scratch);
    EXPECT_EQ(nan.exit_code, 1);
    EXPECT_NE(nan.err.find("pliant: error:"), std::string::npos) << nan.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "nan" / "frames" / "frame_0000.obj"));
}

// A run that cannot go on stops like an interrupt: the frames before the failure, stats.json
// with "error" (the frame and the message), and a clear error (exit 1). Two causes: substeps far
// too long for the cloth (it diverges; a warning says so up front), and 800 layers of a sheet
// stacked 5 µm apart under a 5 mm thickness (the self-collision's pair limit, instead of
// gigabytes of pairs).
TEST(ClothCommand, DivergenceAndOverfullContactStopWithStatsAndAClearError) {
    ScratchDir scratch;
    const CliResult diverge =
        run_scene(scratch, "diverge", R"({"cloth": {"grid": {"size": [2, 2], "quads": [20, 20]}},
            "air": {"wind": [0, -20, 0]}, "fps": 0.5, "substeps": 2, "self_collision": false,
            "frames": 10})");
    EXPECT_EQ(diverge.exit_code, 1);
    EXPECT_NE(diverge.err.find("substeps of 1000 ms"), std::string::npos) << diverge.err;
    EXPECT_NE(diverge.err.find("pliant: error: " + (scratch / "diverge.json").string() + ": frame"),
              std::string::npos)
        << diverge.err;
    EXPECT_NE(diverge.err.find("the simulation diverged"), std::string::npos) << diverge.err;
    const nlohmann::json stats =
        nlohmann::json::parse(read_text(scratch / "diverge" / "stats.json"));
    const int failed = stats.at("error").at("frame").get<int>();
    EXPECT_GT(failed, 1);
    EXPECT_EQ(stats.at("frames").size(), static_cast<std::size_t>(failed - 1));
    EXPECT_FALSE(stats.at("interrupted").get<bool>());
    for (int frame = 0; frame < failed; ++frame) {
        const geometry::TriangleMeshD mesh =
            io::read_mesh(scratch / "diverge" / "frames" / fmt::format("frame_{:04d}.obj", frame));
        for (const Vec3d& p : mesh.positions) {
            EXPECT_TRUE(within_cube(p, 1e9));
        }
    }
    EXPECT_FALSE(std::filesystem::exists(scratch / "diverge" / "frames" /
                                         fmt::format("frame_{:04d}.obj", failed)));

    std::string instances;
    for (int k = 0; k < 800; ++k) {
        instances += fmt::format("{}{{\"translate\": [0, 0, {}]}}", k > 0 ? ", " : "", k * 5e-6);
    }
    const CliResult stack =
        run_scene(scratch, "stack",
                  R"({"cloth": {"grid": {"size": [0.1, 0.1], "quads": [2, 2]}, "instances": [)" +
                      instances + R"(]}, "frames": 1})");
    EXPECT_EQ(stack.exit_code, 1);
    EXPECT_NE(stack.err.find("more than 64 pairs of triangles or 256 pairs of features"),
              std::string::npos)
        << stack.err;
    const nlohmann::json stack_stats =
        nlohmann::json::parse(read_text(scratch / "stack" / "stats.json"));
    EXPECT_EQ(stack_stats.at("error").at("frame"), 1);
    EXPECT_TRUE(std::filesystem::exists(scratch / "stack" / "frames" / "frame_0000.obj"));

    // Two identical instances lie through each other everywhere (6.4 intersecting pairs per
    // triangle): refused before anything is written, untangling or not.
    const CliResult same = run_scene(
        scratch, "same",
        R"({"cloth": {"grid": {"size": [1, 1], "quads": [8, 8]}, "instances": [{}, {}]}})");
    EXPECT_EQ(same.exit_code, 1);
    EXPECT_NE(same.err.find("1648 pairs of triangles"), std::string::npos) << same.err;
    EXPECT_NE(same.err.find("cannot be untangled"), std::string::npos) << same.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "same"));

    // An empty mesh as the cloth or an obstacle names the key; --out "" is a usage error.
    write(scratch / "empty.obj", "");
    const CliResult empty = run_scene(scratch, "empty", R"({"cloth": {"mesh": "empty.obj"}})");
    EXPECT_EQ(empty.exit_code, 1);
    EXPECT_NE(empty.err.find("cloth.mesh"), std::string::npos) << empty.err;
    EXPECT_NE(empty.err.find("at least one triangle"), std::string::npos) << empty.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "empty"));
    const CliResult obstacle = run_scene(
        scratch, "obstacle",
        R"({"cloth": {"grid": {"quads": [2, 2]}}, "obstacles": [{"mesh": {"file": "empty.obj"}}]})",
        "");
    EXPECT_EQ(obstacle.exit_code, 1);
    EXPECT_NE(obstacle.err.find("obstacles[0].mesh.file"), std::string::npos) << obstacle.err;
    write(scratch / "far.obj", "v 0 0 0\nv 1e7 0 0\nv 0 1 0\nf 1 2 3\n");
    const CliResult far = run_scene(scratch, "far", R"({"cloth": {"mesh": "far.obj"}})", "");
    EXPECT_EQ(far.exit_code, 1);
    EXPECT_NE(far.err.find("cloth.mesh"), std::string::npos) << far.err;
    EXPECT_NE(far.err.find("vertex 1 at (10000000, 0, 0): expected coordinates within 1e+06 m"),
              std::string::npos)
        << far.err;
    const CliResult no_out =
        run_cli("cloth " + quoted(scratch / "empty.json") + " --out \"\"", scratch);
    EXPECT_EQ(no_out.exit_code, 2);
    EXPECT_NE(no_out.err.find("--out"), std::string::npos) << no_out.err;
}

// A second run into the same directory leaves frames/ holding exactly its own frames: the
// earlier run's later frames, and those in the other format, are removed once it is done; other
// files stay.
TEST(ClothCommand, RerunLeavesOnlyItsOwnFrames) {
    ScratchDir scratch;
    write(scratch / "s.json",
          R"({"cloth": {"grid": {"size": [1, 1], "quads": [4, 4]}}, "substeps": 2})");
    const std::string run = "cloth " + quoted(scratch / "s.json") + " --out " +
                            quoted(scratch / "out") + " --no-preview --frames ";
    ASSERT_EQ(run_cli(run + "3", scratch).exit_code, 0);
    const std::filesystem::path frames = scratch / "out" / "frames";
    write(frames / "frame_0002.ply", "not ours to keep");
    write(frames / "notes.txt", "mine");
    ASSERT_EQ(run_cli(run + "1", scratch).exit_code, 0);
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(frames)) {
        names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    EXPECT_EQ(names, (std::vector<std::string>{"frame_0000.obj", "frame_0001.obj", "notes.txt"}));
}

TEST(ClothCommand, ADirectoryInTheWayOfAnOutputFileIsAnErrorBeforeAnythingIsWritten) {
    ScratchDir scratch;
    write(scratch / "s.json",
          R"({"cloth": {"grid": {"size": [1, 1], "quads": [4, 4]}}, "substeps": 2})");
    const std::string run =
        "cloth " + quoted(scratch / "s.json") + " --out " + quoted(scratch / "out") + " --frames 3";
    std::vector<std::string> in_the_way = {"stats.json", "frames/frame_0003.obj"};
    if (io::ffmpeg_available()) {
        in_the_way.push_back("preview.mp4");
    }
    for (const std::string& blocked : in_the_way) {
        std::filesystem::remove_all(scratch / "out");
        std::filesystem::create_directories(scratch / "out" / blocked);
        const CliResult r = run_cli(run, scratch);
        EXPECT_EQ(r.exit_code, 1) << blocked;
        EXPECT_NE(
            r.err.find(blocked + ": cannot write the output file: a directory of that name is in "
                                 "the way"),
            std::string::npos)
            << r.err;
        EXPECT_FALSE(std::filesystem::exists(scratch / "out" / "frames" / "frame_0000.obj"))
            << blocked;
    }
    // Not in the way: directories named like a frame this run does not write (beyond its
    // frames, in the other format, with five digits) or like a video it does not write.
    std::filesystem::remove_all(scratch / "out");
    for (const char* name : {"frames/frame_0004.obj", "frames/frame_0002.ply",
                             "frames/frame_00002.obj", "preview.mp4"}) {
        std::filesystem::create_directories(scratch / "out" / name);
    }
    EXPECT_EQ(run_cli(run + " --no-preview", scratch).exit_code, 0);
}

TEST(ClothCommand, AClothTooLargeForItsMemoryIsRefusedBeforeItIsGenerated) {
    ScratchDir scratch;
    // 200 x 200 quads: 80,000 triangles, at least 104 MB with self-collision, 40 MB without.
    write(scratch / "s.json", R"({"cloth": {"grid": {"quads": [200, 200]}}, "frames": 1})");
    const std::string run = "cloth " + quoted(scratch / "s.json") + " --out " +
                            quoted(scratch / "out") + " --no-preview --max-memory ";
    const CliResult r = run_cli(run + "64", scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("cloth.grid of 200 x 200 quads: 80000 triangles need at least 104 MB to "
                         "simulate (1300 bytes per triangle), more than the 67.1 MB of memory "
                         "available"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "out" / "frames"));
    // 100 copies of 4,000 x 4,000 quads: 3.2 billion triangles (terabytes), refused in no time.
    std::string instances;
    for (int k = 0; k < 100; ++k) {
        instances += fmt::format("{}{{\"translate\": [0, 0, {}]}}", k == 0 ? "" : ", ", k);
    }
    write(scratch / "huge.json",
          R"({"cloth": {"grid": {"quads": [4000, 4000]}, "instances": [)" + instances + "]}}");
    const CliResult huge = run_cli("cloth " + quoted(scratch / "huge.json") + " --out " +
                                       quoted(scratch / "out") + " --max-memory 1000000",
                                   scratch);
    EXPECT_EQ(huge.exit_code, 1);
    EXPECT_NE(huge.err.find("cloth.grid of 4000 x 4000 quads in 100 instances: 3200000000 "
                            "triangles need at least 4160.0 GB to simulate"),
              std::string::npos)
        << huge.err;
    // Without self-collision the same sheet needs 40 MB: it runs within 64 MiB of budget.
    write(scratch / "plain.json",
          R"({"cloth": {"grid": {"quads": [200, 200]}}, "frames": 1, "self_collision": false})");
    EXPECT_EQ(run_cli("cloth " + quoted(scratch / "plain.json") + " --out " +
                          quoted(scratch / "plain") + " --no-preview --max-memory 64",
                      scratch)
                  .exit_code,
              0);
    EXPECT_EQ(run_cli(run + "0.5", scratch).exit_code, 2);  // below 1 MiB: a usage error
}

TEST(ClothCommand, SheetsCrossingLikeAnXAreUntangledAndStayApart) {
    // Two instances of a sheet, the second tilted by 20 degrees through the first: a contour
    // from edge to edge, which contour minimization alone does not remove (a region move does).
    ScratchDir scratch;
    write(scratch / "x.json", R"({"cloth": {"grid": {"size": [1, 1], "quads": [24, 24]},
        "instances": [{"translate": [0, 0, 1]},
                      {"rotate_degrees": [20, 0, 0], "translate": [0.0123, 0.0171, 1]}]},
        "obstacles": [{"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}],
        "frames": 6, "substeps": 20})");
    const CliResult r = run_cli("cloth " + quoted(scratch / "x.json") + " --out " +
                                    quoted(scratch / "out") + " --no-preview",
                                scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / "out" / "stats.json"));
    EXPECT_GT(stats.at("initial_intersecting_pairs").get<int>(), 40);
    EXPECT_EQ(stats.at("untangle").at("pairs_left"), 0);
    EXPECT_GE(stats.at("untangle").at("region_moves").get<int>(), 1);
    EXPECT_EQ(stats.at("max_intersecting_pairs"), 0);
}

TEST(ClothCommand, BadScenesNameTheKeyAndWriteNothing) {
    ScratchDir scratch;
    write(scratch / "bad.json", R"({"cloth": {"grid": {}}, "material": {"thicknes": 0.01}})");
    const CliResult r = run_cli(
        "cloth " + quoted(scratch / "bad.json") + " --out " + quoted(scratch / "out"), scratch);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.err.find("pliant: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("material.thicknes"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(scratch / "out"));
    write(scratch / "pins.json",
          R"({"cloth": {"grid": {"quads": [2, 2]}}, "pins": {"vertices": [9]}})");
    const CliResult pins = run_cli(
        "cloth " + quoted(scratch / "pins.json") + " --out " + quoted(scratch / "out"), scratch);
    EXPECT_EQ(pins.exit_code, 1);
    EXPECT_NE(pins.err.find("pins.vertices: vertex 9 out of range"), std::string::npos) << pins.err;
    const CliResult usage = run_cli("cloth " + quoted(scratch / "pins.json"), scratch);
    EXPECT_EQ(usage.exit_code, 2);
}

}  // namespace
}  // namespace pliant::test
