// `pliant cloth` end to end: frames and stats written, the physics visible in the frames, bad
// scenes rejected with the key named and nothing written.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "integration/run_cli.hpp"
#include "pliant/io/mesh_io.hpp"

namespace pliant::test {
namespace {

void write(const std::filesystem::path& path, const std::string& text) {
    std::ofstream(path) << text;
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
    EXPECT_EQ(stats.at("frames").size(), 30u);
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
    // --frames overrides the scene.
    const CliResult short_run = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                            quoted(scratch / "short") + " --frames 2",
                                        scratch);
    ASSERT_EQ(short_run.exit_code, 0) << short_run.err;
    EXPECT_TRUE(std::filesystem::exists(scratch / "short" / "frames" / "frame_0002.obj"));
    EXPECT_FALSE(std::filesystem::exists(scratch / "short" / "frames" / "frame_0003.obj"));
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
    EXPECT_NE(pins.err.find("pins.vertices"), std::string::npos) << pins.err;
    const CliResult usage = run_cli("cloth " + quoted(scratch / "pins.json"), scratch);
    EXPECT_EQ(usage.exit_code, 2);
}

}  // namespace
}  // namespace pliant::test
