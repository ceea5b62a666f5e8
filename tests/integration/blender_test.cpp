// PLY garment frames and the MDD point cache read by Blender's own importers (Blender 3.4's
// io_mesh_ply and io_shape_mdd, tests/integration/blender_readback.py): the quads, their UVs and
// the cache's last frame as `pliant cloth` wrote them. Skips when `blender` is not installed.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "run_cli.hpp"

namespace pliant::test {
namespace {

constexpr int M = 3;  // quads per side

// One panel of M × M quads, 30 cm square, 50 cm up, UV (i / M, j / M) per vertex.
std::string panel_ply() {
    std::ostringstream ply;
    ply << "ply\nformat ascii 1.0\nelement vertex " << (M + 1) * (M + 1)
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float s\n"
           "property float t\nelement face "
        << M * M << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j <= M; ++j) {
        for (int i = 0; i <= M; ++i) {
            ply << i * 0.1 << " " << j * 0.1 << " 0.5 " << static_cast<double>(i) / M << " "
                << static_cast<double>(j) / M << "\n";
        }
    }
    for (int j = 0; j < M; ++j) {
        for (int i = 0; i < M; ++i) {
            const int a = j * (M + 1) + i;
            ply << "4 " << a << " " << a + 1 << " " << a + M + 2 << " " << a + M + 1 << "\n";
        }
    }
    return ply.str();
}

TEST(BlenderReadback, PlyGarmentFramesAndMddCache) {
    if (std::system("command -v blender >/dev/null 2>&1") != 0) {
        GTEST_SKIP() << "blender is not installed";
    }
    ScratchDir scratch;
    std::ofstream(scratch / "panel.ply") << panel_ply();
    std::ofstream(scratch / "scene.json")
        << R"({"cloth": {"mesh": "panel.ply"}, "pins": {"vertices": [12, 15]}, "fps": 24,
               "frames": 3, "substeps": 10,
               "output": {"format": "ply", "point_cache": "mdd"}})";
    const CliResult run = run_cli("cloth " + quoted(scratch / "scene.json") + " --out " +
                                      quoted(scratch / "out") + " --no-preview",
                                  scratch);
    ASSERT_EQ(run.exit_code, 0) << run.err;

    const std::filesystem::path script =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "tests" / "integration" / "blender_readback.py";
    const std::string command = "blender -b --factory-startup --python " + quoted(script) + " -- " +
                                quoted(scratch / "out") + " >" + quoted(scratch / "blender.txt") +
                                " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << read_text(scratch / "blender.txt");
    std::map<std::string, std::string> seen;
    std::istringstream lines(read_text(scratch / "blender.txt"));
    for (std::string line; std::getline(lines, line);) {
        const std::size_t space = line.find(' ');
        seen[line.substr(0, space)] = space == std::string::npos ? "" : line.substr(space + 1);
    }
    ASSERT_EQ(seen.count("done"), 1u) << read_text(scratch / "blender.txt");
    EXPECT_EQ(seen["vertices"], std::to_string((M + 1) * (M + 1)));
    EXPECT_EQ(seen["polygons"], std::to_string(M * M));
    EXPECT_EQ(seen["corners"], "4 4 4 4 4 4 4 4 4");
    EXPECT_EQ(seen["uv_layers"], "1");
    // Every corner's UV is its vertex's (i / M, j / M).
    std::istringstream uvs(seen["loop_uvs"]);
    int num_loops = 0;
    for (std::string item; uvs >> item; ++num_loops) {
        const int v = std::stoi(item.substr(0, item.find(':')));
        const double u = std::stod(item.substr(item.find(':') + 1));
        const double t = std::stod(item.substr(item.find(',') + 1));
        EXPECT_NEAR(u, static_cast<double>(v % (M + 1)) / M, 1e-6) << item;
        EXPECT_NEAR(t, static_cast<double>(v / (M + 1)) / M, 1e-6) << item;
    }
    EXPECT_EQ(num_loops, 4 * M * M);
    EXPECT_EQ(seen["shape_keys"], "4");  // frames 0 … 3
    EXPECT_EQ(seen["mdd_last_vs_ply_last"], "0");
}

}  // namespace
}  // namespace pliant::test
