// The built-in skirt scene: written, read back as a scene, sewn closed within its first frames
// and intersection-free on the walking body; the mannequin is scripts/make-body's.
#include "pliant/pipeline/garment_scene.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"
#include "pliant/pipeline/mannequin.hpp"
#include "support/test_files.hpp"

namespace pliant::pipeline {
namespace {

TEST(GarmentScene, SkirtIsSewnAndStaysIntersectionFree) {
    const io::test::TempDir temp;
    const char* keep = std::getenv("PLIANT_KEEP_SKIRT_SCENE");  // a directory to keep it in
    const std::filesystem::path dir = keep != nullptr ? std::filesystem::path(keep) : temp.path();
    const cloth::ClothScene scene = read_cloth_scene(write_skirt_scene(dir));
    ASSERT_EQ(scene.seams.size(), 1u);
    EXPECT_EQ(scene.seams[0].a.size(), 50u);
    EXPECT_EQ(scene.material_preset, "cotton");
    ClothSimulation sim = ClothSimulation::from_scene(scene, "skirt");
    ASSERT_TRUE(sim.setup().garment);
    EXPECT_EQ(sim.setup().garment->num_faces(), 2u * 24u * 24u);
    EXPECT_EQ(sim.start().initial_intersections, 0);
    const cloth::Seams& seams = sim.solver().model().seams();
    // Placed 6 mm apart at the seams, sewn to the 5 mm thickness (garment_scene.cpp).
    EXPECT_NEAR(seams.max_opening(sim.solver().positions()), 0.001, 1e-4);
    const int frames = keep != nullptr ? scene.frames : 12;
    for (int f = 1; f <= frames; ++f) {
        sim.step();
        ASSERT_EQ(
            collision::count_intersecting_pairs(sim.solver().positions(), sim.solver().triangles()),
            0)
            << "frame " << f;
        if (f >= 6) {  // sewn in 0.1 s (2.4 frames)
            EXPECT_LT(seams.max_opening(sim.solver().positions()), 0.0015) << "frame " << f;
        }
    }
}

// scenes/garment/ is what write_skirt_scene writes (regenerate it with
// PLIANT_KEEP_SKIRT_SCENE=scenes/garment build/release/tests/pipeline/test_pipeline_garment_scene
// --gtest_filter='*Sewn*').
TEST(GarmentScene, CheckedInFilesAreTheGenerators) {
    const io::test::TempDir temp;
    write_skirt_scene(temp.path());
    const std::filesystem::path checked_in =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / "garment";
    std::vector<std::string> names{"scene.json", "skirt.obj", "skirt.mtl"};
    for (int k = 0; k < 12; ++k) {
        names.push_back(fmt::format("body/frame_{:04d}.obj", k));
    }
    for (const std::string& name : names) {
        EXPECT_EQ(io::test::read_bytes(checked_in / name), io::test::read_bytes(temp / name))
            << name;
    }
    EXPECT_FALSE(std::filesystem::exists(temp / "body" / "frame_0012.obj"));
}

// The library's mannequin is scripts/make-body's: the same vertices (to the 6 decimals both
// write) and triangles, frame by frame.
TEST(Mannequin, IsTheOneScriptsMakeBodyWrites) {
    const std::filesystem::path python = "/usr/bin/python3";
    if (!std::filesystem::exists(python)) {
        GTEST_SKIP() << "no " << python;
    }
    const io::test::TempDir temp;
    const std::string command =
        python.string() + " " +
        (std::filesystem::path(PLIANT_SOURCE_DIR) / "scripts" / "make-body").string() + " " +
        (temp / "body").string() + " --frames 5 --segments 7 --turn 40 --swing 15";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    const MannequinOptions options{.segments = 7, .turn_degrees = 40.0, .swing_degrees = 15.0};
    for (int k = 0; k < 5; ++k) {
        const std::string script =
            io::test::read_bytes(temp / "body" / fmt::format("frame_{:04d}.obj", k));
        const std::string ours = mesh_obj(mannequin_at(k / 5.0, options), "");
        // Both without their comment lines.
        EXPECT_EQ(script.substr(script.find('\n') + 1), ours.substr(ours.find('\n') + 1))
            << "frame " << k;
    }
    const geometry::TriangleMeshD body = mannequin_at(0.0);
    EXPECT_EQ(body.positions.size(), 852u);
    EXPECT_EQ(body.triangles.size(), 1680u);
    EXPECT_THROW(mannequin_at(0.0, {.segments = 2}), InvalidInput);
}

}  // namespace
}  // namespace pliant::pipeline
