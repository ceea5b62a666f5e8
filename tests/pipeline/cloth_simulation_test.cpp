// ClothSimulation against the solver it wraps: stepping frame by frame gives the same positions,
// bit for bit, as a ClothSolver built and stepped by hand from the same scene; reset() returns to
// the start; divergence is reported; check() counts intersections exactly.
#include "pliant/pipeline/cloth_simulation.hpp"

#include <gtest/gtest.h>

#include <string>

#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/error.hpp"
#include "pliant/pipeline/cloth_scene_file.hpp"
#include "pliant/pipeline/cloth_setup.hpp"

namespace pliant::pipeline {
namespace {

// A small sheet falling onto a sphere: contact with the obstacle and with itself within frames.
constexpr const char* SCENE = R"({
  "cloth": {"grid": {"size": [1.0, 1.0], "quads": [12, 12]}, "translate": [0, 0, 0.6]},
  "obstacles": [{"sphere": {"center": [0, 0, 0], "radius": 0.3}}],
  "frames": 6, "fps": 24, "substeps": 10
})";

cloth::ClothScene small_scene() {
    return parse_cloth_scene(SCENE, "small", ".");
}

TEST(ClothSimulation, StepsAsTheSolverBuiltByHand) {
    ClothSimulation sim = ClothSimulation::from_scene(small_scene(), "small");
    const cloth::ClothScene scene = small_scene();
    const ClothSetup setup = load_cloth_setup(scene, "small");
    const std::unique_ptr<cloth::ClothSolver> reference = make_solver(scene, setup);
    prepare_start(scene, "small", *reference);
    for (int f = 1; f <= scene.frames; ++f) {
        sim.step();
        reference->step(1.0 / scene.frames_per_second, scene.substeps);
        EXPECT_EQ(sim.frame(), f);
        ASSERT_EQ(sim.positions().size(), reference->positions().size());
        for (std::size_t v = 0; v < sim.positions().size(); ++v) {
            ASSERT_EQ(sim.positions()[v], reference->positions()[v])
                << "frame " << f << " vertex " << v;
        }
    }
    EXPECT_DOUBLE_EQ(sim.time(), reference->time());
}

TEST(ClothSimulation, ResetReturnsToTheStart) {
    ClothSimulation sim = ClothSimulation::from_scene(small_scene(), "small");
    const std::vector<Vec3d> start(sim.positions().begin(), sim.positions().end());
    sim.step();
    sim.step();
    const std::vector<Vec3d> after_two(sim.positions().begin(), sim.positions().end());
    EXPECT_NE(after_two, start);
    sim.reset();
    EXPECT_EQ(sim.frame(), 0);
    EXPECT_EQ(std::vector<Vec3d>(sim.positions().begin(), sim.positions().end()), start);
    sim.step();
    sim.step();
    EXPECT_EQ(std::vector<Vec3d>(sim.positions().begin(), sim.positions().end()), after_two);
}

TEST(ClothSimulation, CheckCountsIntersectionsAndStrain) {
    ClothSimulation sim = ClothSimulation::from_scene(small_scene(), "small");
    const ClothFrameCheck at_start = sim.check();
    EXPECT_EQ(at_start.intersecting_pairs, 0);
    EXPECT_EQ(at_start.strain.max, 0.0);  // the start is the rest shape
    for (int f = 0; f < 6; ++f) {
        sim.step();
    }
    const ClothFrameCheck later = sim.check();
    EXPECT_EQ(later.intersecting_pairs,
              collision::count_intersecting_pairs(sim.positions(), sim.triangles()));
    EXPECT_GT(later.strain.max, 0.0);
}

TEST(ClothSimulation, DivergenceIsReported) {
    cloth::ClothScene scene = small_scene();
    scene.gravity = {0.0, 0.0, -1e14};  // m/s²: beyond MAX_COORDINATE within a frame
    scene.obstacles.clear();
    ClothSimulation sim = ClothSimulation::from_scene(scene, "small");
    try {
        sim.step();
        FAIL() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("the simulation diverged"), std::string::npos)
            << e.what();
    }
}

TEST(ClothSimulation, MissingMeshFileNamesTheScene) {
    cloth::ClothScene scene = small_scene();
    scene.grid.reset();
    scene.mesh = "no/such/cloth.obj";
    EXPECT_THROW(ClothSimulation::from_scene(scene, "small"), IoError);
}

// A simulation that loads the state of another continues bit for bit: positions after 3 more
// frames equal those of the original, which ran on without the round trip.
TEST(ClothSimulation, SavedStateContinuesBitForBit) {
    ClothSimulation original = ClothSimulation::from_scene(small_scene(), "small");
    for (int f = 0; f < 3; ++f) {
        original.step();
    }
    ByteWriter saved;
    original.save_state(saved);
    ClothSimulation resumed = ClothSimulation::from_scene(small_scene(), "small");
    ByteReader in(saved.bytes(), "state");
    resumed.load_state(in);
    in.expect_end();
    EXPECT_EQ(resumed.frame(), 3);
    for (int f = 0; f < 3; ++f) {
        original.step();
        resumed.step();
        for (std::size_t v = 0; v < original.positions().size(); ++v) {
            ASSERT_EQ(original.positions()[v], resumed.positions()[v])
                << "frame " << original.frame() << " vertex " << v;
        }
    }
    EXPECT_EQ(original.time(), resumed.time());
    // A truncated state is refused with the field named.
    ClothSimulation other = ClothSimulation::from_scene(small_scene(), "small");
    ByteReader truncated(saved.bytes().first(saved.size() / 2), "state");
    EXPECT_THROW(other.load_state(truncated), InvalidInput);
}

}  // namespace
}  // namespace pliant::pipeline
