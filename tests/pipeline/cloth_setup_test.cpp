// load_cloth_setup and make_solver for deforming mesh obstacles ("frames") and attached pins:
// frame files found by pattern or list, one topology checked, bad files named.
#include "pliant/pipeline/cloth_setup.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "support/test_files.hpp"

namespace pliant::pipeline {
namespace {

using io::test::TempDir;
using io::test::write_bytes;

// A tetrahedron (closed, outward) raised by dz, as OBJ text; `extra` appended.
std::string tetrahedron(double dz, const std::string& extra = "") {
    return fmt::format(
        "v 0 0 {0}\nv 1 0 {0}\nv 0 1 {0}\nv 0 0 {1}\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n{2}", dz,
        dz + 1.0, extra);
}

cloth::ClothScene scene_with(const TempDir& dir, const std::string& obstacle) {
    const std::string text = R"({"cloth": {"grid": {"size": [0.2, 0.2], "quads": [2, 2]},
                                           "translate": [0.2, 0.2, 1.3]},
                                 "pins": {"vertices": [0], "attach": {"obstacle": 0,
                                                                      "max_distance": 0.5}},
                                 "obstacles": [)" +
                             obstacle + "], \"fps\": 10, \"self_collision\": false}";
    return parse_cloth_scene(text, "scene.json", dir.path());
}

std::string error_of(const cloth::ClothScene& scene) {
    try {
        load_cloth_setup(scene, "scene.json");
    } catch (const InvalidInput& e) {
        return e.what();
    } catch (const IoError& e) {
        return e.what();
    }
    return "no error";
}

TEST(ClothSetup, ReadsFramesByPatternAndTheSolverFollowsThem) {
    TempDir dir;
    std::filesystem::create_directories(dir / "body");
    for (int k = 1; k <= 3; ++k) {  // no frame 0: numbering starts at 1
        write_bytes(dir / fmt::format("body/f_{:03d}.obj", k), tetrahedron(0.1 * (k - 1)));
    }
    const cloth::ClothScene scene =
        scene_with(dir, R"({"mesh": {"frames": "body/f_%03d.obj", "fps": 10}})");
    const ClothSetup setup = load_cloth_setup(scene, "scene.json");
    ASSERT_TRUE(setup.animations[0]);
    EXPECT_EQ(setup.animations[0]->num_frames(), 3u);
    EXPECT_EQ(setup.animations[0]->fps(), 10.0);
    EXPECT_EQ(setup.animations[0]->frame(2)[0], (Vec3d{0.0, 0.0, 0.2}));
    // The pinned vertex rides on the tetrahedron's slanted face as it rises 0.2 m in 0.2 s.
    auto solver = make_solver(scene, setup);
    const Vec3d start = solver->positions()[0];
    for (int frame = 0; frame < 3; ++frame) {
        solver->step(0.1, 4);
    }
    const Vec3d end = solver->positions()[0];
    EXPECT_NEAR(end.z - start.z, 0.2, 1e-12);
    EXPECT_NEAR(end.x, start.x, 1e-12);
    // A list of files, with a count beyond them, and one of the files missing.
    EXPECT_NE(
        error_of(
            scene_with(dir, R"({"mesh": {"frames": "body/f_%03d.obj", "start": 1, "count": 4}})"))
            .find("frame file " + (dir / "body/f_004.obj").string() + " is missing"),
        std::string::npos);
    EXPECT_NE(error_of(scene_with(dir, R"({"mesh": {"frames": "body/g_%03d.obj"}})"))
                  .find("no file matches"),
              std::string::npos);
    EXPECT_NE(error_of(scene_with(dir, R"({"mesh": {"frames": "body/f_%03d_%d.obj"}})"))
                  .find("one frame number"),
              std::string::npos);
    EXPECT_NE(
        error_of(scene_with(dir, R"({"mesh": {"frames": "body/f.obj"}})")).find("one frame number"),
        std::string::npos);
    EXPECT_NE(
        error_of(scene_with(dir, R"({"mesh": {"frames": ["body/f_001.obj", "body/nope.obj"]}})"))
            .find("nope.obj"),
        std::string::npos);
}

TEST(ClothSetup, FramesOfAnotherTopologyOrNotFiniteAreErrors) {
    TempDir dir;
    write_bytes(dir / "a.obj", tetrahedron(0.0));
    write_bytes(dir / "more.obj", tetrahedron(0.1, "v 5 5 5\n"));
    write_bytes(dir / "other.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    write_bytes(dir / "nan.obj",
                "v 0 0 nan\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n");
    const std::string more =
        error_of(scene_with(dir, R"({"mesh": {"frames": ["a.obj", "more.obj"]}})"));
    EXPECT_NE(more.find("obstacles[0].mesh.frames: frame 1"), std::string::npos) << more;
    EXPECT_NE(more.find("has 5 vertices and 4 triangles, frame 0 has 4 and 4"), std::string::npos)
        << more;
    const std::string other =
        error_of(scene_with(dir, R"({"mesh": {"frames": ["a.obj", "other.obj"]}})"));
    EXPECT_NE(other.find("triangle 0 is (0, 1, 2), in frame 0 (0, 2, 1)"), std::string::npos)
        << other;
    const std::string nan =
        error_of(scene_with(dir, R"({"mesh": {"frames": ["a.obj", "nan.obj"]}})"));
    EXPECT_NE(nan.find("nan.obj"), std::string::npos) << nan;
}

}  // namespace
}  // namespace pliant::pipeline
