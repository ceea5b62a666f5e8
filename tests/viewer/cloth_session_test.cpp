#include "cloth_session.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::viewer {
namespace {

// A 0.6 m sheet of 12 × 12 quads falling onto a sphere, self-collision on, 20 substeps per frame.
cloth::ClothScene small_scene() {
    cloth::ClothScene scene;
    scene.grid = cloth::GridSheet{{0.6, 0.6}, {12, 12}};
    scene.translate = {0.0, 0.0, 0.35};
    cloth::SceneObstacle sphere;
    sphere.shape = cloth::SphereObstacle{{0.0, 0.0, 0.0}, 0.2};
    scene.obstacles.push_back(sphere);
    scene.material.thickness = 0.004;
    scene.substeps = 20;
    scene.frames_per_second = 24.0;
    return scene;
}

bool same_positions(std::span<const Vec3d> a, std::span<const Vec3d> b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3d)) == 0;
}

// Frames of 4 substeps (one self-collision window) land bitwise on `pliant cloth`'s frames of
// 20 substeps: the same solver, the same substep, windows on the same substeps.
TEST(ClothSession, WindowFramesLandOnTheScenesFrames) {
    const cloth::ClothScene scene = small_scene();
    ClothSession session(scene, "small", {.substeps_per_frame = 4, .check_every = 10});
    const pipeline::ClothSetup setup = pipeline::load_cloth_setup(scene, "small");
    const std::unique_ptr<cloth::ClothSolver> reference = pipeline::make_solver(scene, setup);
    for (int scene_frame = 1; scene_frame <= 6; ++scene_frame) {
        for (int k = 0; k < 5; ++k) {
            session.advance();
        }
        reference->step(1.0 / 24.0, 20);
        ASSERT_TRUE(same_positions(session.positions(), reference->positions()))
            << "scene frame " << scene_frame;
    }
    EXPECT_EQ(session.frame(), 30);
    EXPECT_NEAR(session.time(), 0.25, 1e-12);
    EXPECT_TRUE(session.stats().step.has_self_collision);
    // The exact count ran after frames 1, 10, 20 and 30.
    EXPECT_EQ(session.stats().checked_frame, 30);
    EXPECT_EQ(session.stats().intersecting_pairs, 0);
    // One frame of the scene's 20 substeps is one frame of `pliant cloth`.
    session.set_substeps_per_frame(20);
    session.advance();
    reference->step(1.0 / 24.0, 20);
    EXPECT_TRUE(same_positions(session.positions(), reference->positions()));
}

// A scene that starts intersecting itself starts untangled, as `pliant cloth` starts it (and
// stays reported only when the scene says "untangle": false).
TEST(ClothSession, StartsUntangledAsTheCommandDoes) {
    cloth::ClothScene scene;
    scene.grid = cloth::GridSheet{{1.0, 1.0}, {16, 16}};
    scene.instances = {cloth::Placement{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}},
                       cloth::Placement{{20.0, 0.0, 0.0}, {0.0123, 0.0171, 1.0}}};
    scene.substeps = 10;
    ClothSession session(scene, "crossing", {.substeps_per_frame = 10, .check_every = 1});
    EXPECT_GT(session.start().initial_intersections, 20);
    ASSERT_TRUE(session.start().untangled.has_value());
    EXPECT_EQ(session.start().untangled->final_pairs, 0);
    EXPECT_EQ(session.stats().intersecting_pairs, 0);
    const pipeline::ClothSetup setup = pipeline::load_cloth_setup(scene, "crossing");
    const std::unique_ptr<cloth::ClothSolver> reference = pipeline::make_solver(scene, setup);
    pipeline::prepare_start(scene, "crossing", *reference);
    EXPECT_TRUE(same_positions(session.positions(), reference->positions()));

    // Reset reuses the start rather than untangling again (the same report, to the timing),
    // and simulates from it as before.
    session.advance();
    const std::vector<Vec3d> first_frame(session.positions().begin(), session.positions().end());
    const double untangle_ms = session.start().untangled->ms;
    session.reset();
    EXPECT_TRUE(same_positions(session.positions(), reference->positions()));
    EXPECT_EQ(session.start().untangled->ms, untangle_ms);
    EXPECT_EQ(session.stats().intersecting_pairs, 0);
    session.advance();
    EXPECT_TRUE(same_positions(session.positions(), first_frame));

    scene.untangle = false;
    ClothSession reported(scene, "crossing", {.substeps_per_frame = 10, .check_every = 1});
    EXPECT_FALSE(reported.start().untangled.has_value());
    EXPECT_EQ(reported.stats().intersecting_pairs, reported.start().initial_intersections);
}

// In the background: the published state stays the last one until the frame in flight is
// published, one frame at a time, and the states are those of advance().
TEST(ClothSession, BackgroundFramesPublishTheSameStates) {
    ClothSession background(small_scene(), "small");
    ClothSession foreground(small_scene(), "small");
    for (int f = 1; f <= 5; ++f) {
        const std::vector<Vec3d> before(background.positions().begin(),
                                        background.positions().end());
        ASSERT_TRUE(background.start_advance());
        EXPECT_TRUE(background.is_advancing());
        EXPECT_FALSE(background.start_advance());  // one frame in flight at a time
        EXPECT_TRUE(same_positions(background.positions(), before));
        EXPECT_EQ(background.frame(), f - 1);
        while (!background.finish_advance(false)) {
        }
        EXPECT_FALSE(background.is_advancing());
        EXPECT_FALSE(background.finish_advance(true));  // nothing in flight
        foreground.advance();
        EXPECT_EQ(background.frame(), f);
        EXPECT_TRUE(same_positions(background.positions(), foreground.positions()));
    }
    // reset() waits for a frame in flight and drops it.
    const ClothSession fresh(small_scene(), "small");
    background.start_advance();
    background.reset();
    EXPECT_FALSE(background.is_advancing());
    EXPECT_EQ(background.frame(), 0);
    EXPECT_TRUE(same_positions(background.positions(), fresh.positions()));
}

TEST(ClothSession, GrabDragsTheVertexUnderTheCursorAndResetRestores) {
    ClothSession session(small_scene(), "small");
    const std::vector<Vec3d> start(session.positions().begin(), session.positions().end());
    const render::Camera camera = render::Camera::perspective({0.0, -1.5, 1.5}, {0.0, 0.0, 0.3},
                                                              {0.0, 0.0, 1.0}, 35.0, 400, 300);
    // A point of the sheet near vertex v (not on it: see the picking tests).
    const std::size_t v = 7 * 13 + 5;
    const Vec3d near_v = start[v] + Vec3d{0.004, 0.003, 0.0};
    const render::PixelPoint pixel = camera.project(near_v);
    ASSERT_TRUE(session.begin_grab(camera, pixel.x, pixel.y));
    EXPECT_EQ(session.grabbed_vertex(), static_cast<std::int32_t>(v));
    // Drag 40 pixels up: after the next frame the vertex is where the cursor points, at the
    // depth it was grabbed at.
    session.drag(camera, pixel.x, pixel.y - 40.0);
    session.advance();
    const Vec3d& moved = session.positions()[v];
    const render::PixelPoint now = camera.project(moved);
    EXPECT_NEAR(now.y, pixel.y - 40.0, 0.5);
    EXPECT_GT(moved.z, start[v].z + 0.02);
    session.end_grab();
    EXPECT_EQ(session.grabbed_vertex(), -1);
    // Nothing under the cursor: no grab.
    EXPECT_FALSE(session.begin_grab(camera, 1.0, 1.0));
    session.reset();
    EXPECT_EQ(session.frame(), 0);
    EXPECT_TRUE(same_positions(session.positions(), start));
    EXPECT_EQ(session.stats().checked_frame, 0);
}

TEST(ClothSession, BoxesAndErrors) {
    cloth::ClothScene scene = small_scene();
    cloth::SceneObstacle floor;
    floor.shape = cloth::PlaneObstacle{{0.0, 0.0, -0.3}, {0.0, 0.0, 1.0}};
    scene.obstacles.push_back(floor);
    const ClothSession session(scene, "small");
    // The framing box holds the sheet and the sphere, not the floor's square; the scene box
    // holds the floor too.
    EXPECT_NEAR(session.framing_box().lo.z, -0.2, 1e-9);
    EXPECT_NEAR(session.framing_box().hi.z, 0.35, 1e-9);
    EXPECT_NEAR(session.scene_box().lo.z, -0.3, 1e-9);
    EXPECT_GT(session.scene_box().hi.x, session.framing_box().hi.x);
    EXPECT_THROW(ClothSession(scene, "x", {.substeps_per_frame = 0}), InvalidInput);
    EXPECT_THROW(ClothSession(scene, "x", {.check_every = 0}), InvalidInput);
    cloth::ClothScene missing = small_scene();
    missing.grid.reset();
    missing.mesh = "/nonexistent/cloth.obj";
    EXPECT_THROW(ClothSession(missing, "missing"), IoError);
}

}  // namespace
}  // namespace pliant::viewer
