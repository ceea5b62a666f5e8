// The built-in skirt scene: written, read back as a scene, sewn closed within its first frames
// and intersection-free on the turning body.
#include "pliant/pipeline/garment_scene.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_simulation.hpp"
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
    EXPECT_GT(seams.max_opening(sim.solver().positions()), 0.01);
    const int frames = keep != nullptr ? scene.frames : 12;
    for (int f = 1; f <= frames; ++f) {
        sim.step();
        ASSERT_EQ(
            collision::count_intersecting_pairs(sim.solver().positions(), sim.solver().triangles()),
            0)
            << "frame " << f;
        if (f >= 6) {  // sewn in 0.1 s (2.4 frames)
            EXPECT_LT(seams.max_opening(sim.solver().positions()), 0.002) << "frame " << f;
        }
    }
}

// scenes/garment/ is what write_skirt_scene writes (regenerate it with
// PLIANT_KEEP_SKIRT_SCENE=scenes/garment build/release/tests/pipeline/test_pipeline_garment_scene).
TEST(GarmentScene, CheckedInFilesAreTheGenerators) {
    const io::test::TempDir temp;
    write_skirt_scene(temp.path());
    const std::filesystem::path checked_in =
        std::filesystem::path(PLIANT_SOURCE_DIR) / "scenes" / "garment";
    for (const char* name : {"scene.json", "skirt.obj", "skirt.mtl", "body.obj"}) {
        EXPECT_EQ(io::test::read_bytes(checked_in / name), io::test::read_bytes(temp / name))
            << name;
    }
}

}  // namespace
}  // namespace pliant::pipeline
