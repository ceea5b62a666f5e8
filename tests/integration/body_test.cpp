// A sheet falling onto an animated, deforming mannequin (scenes/stress/cloth_on_turning_body.json,
// made by scripts/make-body): every written frame is intersection-free by the exact check, no
// cloth vertex is inside the body and no cloth edge crosses its surface, judged independently of
// the solver (body_checks.hpp: the generalized winding number of the body's closed surface at
// that frame's time, exact segment-triangle tests).
// Also the bad frame sequences and attachments a user can write, through the command line.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "integration/body_checks.hpp"
#include "integration/run_cli.hpp"
#include "pliant/geometry/triangle_mesh.hpp"
#include "pliant/io/mesh_io.hpp"

namespace pliant::test {
namespace {

const std::filesystem::path SCENES = std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes";

TEST(BodyScene, ClothOnATurningBodyNeverEntersItAndStaysIntersectionFree) {
    ScratchDir scratch;
    constexpr int FRAMES = 24;  // one walk cycle of the body
    const CliResult r = run_cli(
        "cloth " + quoted(SCENES / "stress" / "cloth_on_turning_body.json") + " --out " +
            quoted(scratch / "out") + " --frames " + std::to_string(FRAMES) + " --no-preview",
        scratch);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = nlohmann::json::parse(read_text(scratch / "out" / "stats.json"));
    ASSERT_EQ(stats.at("frames").size(), static_cast<std::size_t>(FRAMES));
    std::int64_t contacts = 0;
    for (const nlohmann::json& frame : stats.at("frames")) {
        EXPECT_EQ(frame.at("intersecting_pairs"), 0) << frame.at("frame");
        EXPECT_GT(frame.at("obstacle_max_step").get<double>(), 0.0);  // the body moves
        contacts += frame.at("obstacle_contacts").get<std::int64_t>();
    }
    EXPECT_GT(contacts, 0);  // the cloth lands on the body

    // The winding number tells inside from outside: the torso's centre, and a point beside it.
    const geometry::TriangleMeshD body0 =
        io::read_mesh(SCENES / "stress" / "body" / "frame_0000.obj");
    EXPECT_NEAR(winding_number(body0, {0.0, 0.0, 1.2}), 1.0, 1e-9);
    EXPECT_NEAR(winding_number(body0, {0.0, 0.0, 2.5}), 0.0, 1e-9);

    // Scene and body at 24 frames per second, the body looping every 24 frames.
    for (int f = 0; f <= FRAMES; ++f) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d.obj", f);
        const geometry::TriangleMeshD cloth = io::read_mesh(scratch / "out" / "frames" / name);
        std::snprintf(name, sizeof name, "frame_%04d.obj", f % 24);
        const geometry::TriangleMeshD body = io::read_mesh(SCENES / "stress" / "body" / name);
        EXPECT_EQ(vertices_inside(cloth, body), 0) << "frame " << f << ": cloth vertices inside";
        EXPECT_EQ(edges_crossing(cloth, body), 0) << "frame " << f << ": cloth edges through it";
        EXPECT_EQ(edges_crossing(body, cloth), 0) << "frame " << f << ": body edges through cloth";
    }
}

TEST(BodyScene, ResumedAndThreadedRunsWriteTheSameFrames) {
    ScratchDir scratch;
    const std::string scene = quoted(SCENES / "stress" / "cloth_on_turning_body.json");
    const CliResult whole = run_cli("cloth " + scene + " --out " + quoted(scratch / "whole") +
                                        " --frames 4 --no-preview --threads 2",
                                    scratch);
    ASSERT_EQ(whole.exit_code, 0) << whole.err;
    const CliResult first = run_cli("cloth " + scene + " --out " + quoted(scratch / "parts") +
                                        " --frames 2 --checkpoint-every 2 --no-preview --threads 1",
                                    scratch);
    ASSERT_EQ(first.exit_code, 0) << first.err;
    const CliResult rest = run_cli("cloth " + scene + " --out " + quoted(scratch / "parts") +
                                       " --frames 4 --resume --no-preview --threads 1",
                                   scratch);
    ASSERT_EQ(rest.exit_code, 0) << rest.err;
    for (const char* name : {"frame_0002.obj", "frame_0003.obj", "frame_0004.obj"}) {
        const std::string a = read_text(scratch / "whole" / "frames" / name);
        EXPECT_FALSE(a.empty()) << name;
        EXPECT_TRUE(a == read_text(scratch / "parts" / "frames" / name)) << name;
    }
}

TEST(BodyScene, BadFrameSequencesAndAttachmentsAreClearErrors) {
    ScratchDir scratch;
    const std::string tetrahedron =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
        "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
    std::ofstream(scratch / "a.obj") << tetrahedron;
    std::ofstream(scratch / "more.obj") << tetrahedron << "v 2 2 2\n";
    std::ofstream(scratch / "nan.obj") << "v 0 0 nan\n" << tetrahedron.substr(8);
    const auto run = [&](const std::string& obstacle, const std::string& pins = "") {
        std::ofstream(scratch / "scene.json")
            << R"({"cloth": {"grid": {"size": [0.2, 0.2], "quads": [2, 2]},
                             "translate": [0.2, 0.2, 1.2]},)"
            << pins << R"("obstacles": [)" << obstacle << R"(], "frames": 2})";
        return run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                           quoted(scratch / "out") + " --no-preview",
                       scratch);
    };
    const auto expect_error = [&](const CliResult& r, const std::string& part) {
        EXPECT_EQ(r.exit_code, 1) << r.err;
        EXPECT_EQ(r.err.rfind("pliant: error: ", 0), 0u) << r.err;
        EXPECT_NE(r.err.find(part), std::string::npos) << r.err;
        EXPECT_FALSE(std::filesystem::exists(scratch / "out" / "stats.json"));
    };
    expect_error(run(R"({"mesh": {"frames": "body/frame_%04d.obj"}})"), "no file matches");
    expect_error(run(R"({"mesh": {"frames": "a%d.obj", "count": 3}})"),
                 "obstacles[0].mesh.frames: frame file");
    expect_error(run(R"({"mesh": {"frames": ["a.obj", "more.obj"]}})"),
                 "frame 1 (" + (scratch / "more.obj").string() +
                     ") has 5 vertices and 4 triangles, frame 0 has 4 and 4");
    expect_error(run(R"({"mesh": {"frames": ["a.obj", "nan.obj"]}})"), "nan.obj");
    expect_error(run(R"({"name": "body", "mesh": {"frames": ["a.obj"]}})",
                     R"("pins": {"vertices": [0], "attach": {"obstacle": "bdy"}},)"),
                 "pins.attach.obstacle: expected the name of an obstacle (\"body\"), got \"bdy\"");
    expect_error(run(R"({"name": "body", "mesh": {"frames": ["a.obj"]}})",
                     R"("pins": {"vertices": [0], "attach": {"obstacle": "body",
                                                           "max_distance": 0.01}},)"),
                 "pins.attach: cloth: attached pins: vertex 0");
}

}  // namespace
}  // namespace pliant::test
