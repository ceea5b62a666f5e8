#include "pliant/cloth/cloth_model.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/generate.hpp"
#include "support/sheets.hpp"

namespace pliant::cloth {
namespace {

geometry::TriangleMeshD sheet(int n, double size, double z) {
    return test::flat_sheet(n, size, z);
}

TEST(ClothModel, MassesAreAThirdOfEachTrianglesRestMass) {
    // One right triangle of legs 1 m and 2 m (area 1 m²) and an unused vertex.
    geometry::TriangleMeshD mesh;
    mesh.positions = {{0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 2.0, 0.0}, {5.0, 5.0, 5.0}};
    mesh.triangles = {{0, 1, 2}};
    ClothMaterial material;
    material.areal_density = 0.3;
    const ClothModel model(mesh, material, std::vector<std::int32_t>{2});
    const std::span<const double> w = model.inverse_masses();
    EXPECT_DOUBLE_EQ(w[0], 1.0 / 0.1);
    EXPECT_DOUBLE_EQ(w[1], 1.0 / 0.1);
    EXPECT_EQ(w[2], 0.0);  // pinned
    EXPECT_EQ(w[3], 0.0);  // no area
    EXPECT_EQ(model.time(), 0.0);
    EXPECT_EQ(model.num_vertices(), 4u);
    EXPECT_EQ(model.topology().num_edges(), 3u);
    EXPECT_EQ(model.rest_positions()[3], (Vec3d{5.0, 5.0, 5.0}));
}

TEST(ClothModel, MovesPinsAndObstaclesToATimeWithoutAStepper) {
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 1.0);
    ClothModel model(mesh, ClothMaterial{});
    Motion lift;
    lift.keyframes = {{0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
                      {2.0, {0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}}};
    model.add_moving_pins(std::vector<std::int32_t>{0, 4}, lift);
    Motion slide;
    slide.keyframes = {{0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
                       {1.0, {3.0, 0.0, 0.0}, {0.0, 0.0, 0.0}}};
    model.add_obstacle(SphereObstacle{{0.0, 0.0, -2.0}, 0.5}, slide);
    EXPECT_EQ(model.inverse_masses()[0], 0.0);
    EXPECT_EQ(model.inverse_masses()[4], 0.0);

    model.move_pins(1.0);
    model.move_obstacles(1.0);
    // Halfway up their path; the other vertices stay where they are (a stepper moves them).
    EXPECT_DOUBLE_EQ(model.positions()[0].z, 1.5);
    EXPECT_DOUBLE_EQ(model.positions()[4].z, 1.5);
    EXPECT_EQ(model.positions()[1], mesh.positions[1]);
    const auto* sphere = std::get_if<SphereObstacle>(&model.obstacles()[0].current);
    ASSERT_NE(sphere, nullptr);
    EXPECT_EQ(sphere->center, (Vec3d{3.0, 0.0, -2.0}));
    const auto* before = std::get_if<SphereObstacle>(&model.obstacles()[0].previous);
    ASSERT_NE(before, nullptr);
    EXPECT_EQ(before->center, (Vec3d{0.0, 0.0, -2.0}));
    // Moving obstacles and pins is not a step: the model's time is the steps'.
    EXPECT_EQ(model.time(), 0.0);
    EXPECT_NEAR(model.nearest_obstacle({3.0, 0.0, 0.0}).distance, 1.5, 1e-12);
}

TEST(ClothModel, PinsChaseATargetThatJumpsAtABoundedSpeed) {
    // Vertices 0 and 4 jump 1 m up at once; 4 is also in a later static group, which it follows.
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 1.0);
    ClothModel model(mesh, ClothMaterial{});
    Motion jump;
    jump.keyframes = {{0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
                      {0.001, {0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}}};
    model.add_moving_pins(std::vector<std::int32_t>{0, 4}, jump);
    model.add_moving_pins(std::vector<std::int32_t>{4}, Motion{});
    EXPECT_EQ(model.pin_lag().vertices, 0);
    const double max_step = 0.3;
    for (int step = 1; step <= 4; ++step) {
        model.begin_step(0.1);
        model.move_pins(0.1 * step, max_step);
        model.end_step();
        // At most max_step per call toward the target, then exactly on it.
        const double expected = std::min(1.0, max_step * step);
        EXPECT_NEAR(model.positions()[0].z, 1.0 + expected, 1e-12) << step;
        EXPECT_EQ(model.positions()[4], mesh.positions[4]);
        const ClothModel::PinLag lag = model.pin_lag();
        EXPECT_EQ(lag.vertices, step < 4 ? 1 : 0) << step;
        EXPECT_NEAR(lag.max, 1.0 - expected, 1e-12) << step;
    }
    EXPECT_EQ(model.positions()[0].z, 2.0);  // the target itself, not a sum of steps
    // Without a bound, the target at once.
    ClothModel unbounded(mesh, ClothMaterial{});
    unbounded.add_moving_pins(std::vector<std::int32_t>{0}, jump);
    unbounded.move_pins(0.1);
    EXPECT_EQ(unbounded.positions()[0].z, 2.0);
}

TEST(ClothModel, GrabFollowsItsPathOverAStep) {
    const geometry::TriangleMeshD mesh = sheet(2, 1.0, 0.0);
    ClothModel model(mesh, ClothMaterial{});
    const Vec3d start = model.positions()[4];
    const Vec3d target = start + Vec3d{0.0, 0.0, 0.4};
    model.grab(4, target);
    EXPECT_EQ(model.grabbed_vertex(), 4);
    EXPECT_EQ(model.inverse_masses()[4], 0.0);
    model.begin_step(0.1);
    model.move_pins(0.025);
    EXPECT_DOUBLE_EQ(model.positions()[4].z, 0.1);
    model.move_pins(0.1);
    EXPECT_EQ(model.positions()[4], target);
    model.end_step();
    EXPECT_DOUBLE_EQ(model.time(), 0.1);
    model.release_grab();
    EXPECT_EQ(model.grabbed_vertex(), -1);
    EXPECT_GT(model.inverse_masses()[4], 0.0);
}

TEST(ClothModel, ReportsPenetrationAndCountsPositionResets) {
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 0.0);
    ClothModel model(mesh, ClothMaterial{});
    EXPECT_FALSE(model.has_obstacles());
    EXPECT_EQ(model.obstacle_penetration().vertices, 0);
    model.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.1}, {0.0, 0.0, 1.0}});
    const ClothModel::Penetration inside = model.obstacle_penetration();
    EXPECT_EQ(inside.vertices, 25);
    EXPECT_NEAR(inside.deepest, 0.1, 1e-12);

    EXPECT_EQ(model.num_position_resets(), 0);
    std::vector<Vec3d> lifted(model.positions().begin(), model.positions().end());
    for (Vec3d& p : lifted) {
        p.z = 0.2;
    }
    model.set_positions(lifted);
    EXPECT_EQ(model.num_position_resets(), 1);
    EXPECT_EQ(model.obstacle_penetration().vertices, 0);
    // Nothing to untangle: the positions are not replaced.
    EXPECT_EQ(model.untangle().iterations, 0);
    EXPECT_EQ(model.num_position_resets(), 1);
}

TEST(ClothModel, AirSlowsAFallingSheetAndNothingWithoutAir) {
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 0.0);
    ClothModel model(mesh, ClothMaterial{});
    model.set_velocities(std::vector<Vec3d>(mesh.positions.size(), Vec3d{0.0, 0.0, -5.0}));
    model.apply_air(0.01, 0.0);  // no air: no change
    EXPECT_EQ(model.velocities()[12], (Vec3d{0.0, 0.0, -5.0}));
    Air air;
    air.density = 1.2;
    model.set_air(air);
    model.apply_air(0.01, 0.0);
    const Vec3d v = model.velocities()[12];
    EXPECT_GT(v.z, -5.0);
    EXPECT_LT(v.z, 0.0);
    EXPECT_NEAR(v.x, 0.0, 1e-12);
    EXPECT_NEAR(v.y, 0.0, 1e-12);
}

TEST(ClothModel, RejectsBadInputNamingIt) {
    const geometry::TriangleMeshD mesh = sheet(2, 1.0, 0.0);
    ClothModel model(mesh, ClothMaterial{}, std::vector<std::int32_t>{0});
    Motion turn;
    turn.keyframes = {{0.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}},
                      {1.0, {0.0, 0.0, 0.0}, {0.0, 0.0, 90.0}}};
    EXPECT_THROW(model.add_obstacle(BoxObstacle{}, turn), InvalidInput);
    EXPECT_THROW(model.add_mesh_obstacle(nullptr), InvalidInput);
    EXPECT_THROW(model.grab(9, {0.0, 0.0, 0.0}), InvalidInput);
    std::vector<Vec3d> moved(model.positions().begin(), model.positions().end());
    moved[0].z += 0.1;
    try {
        model.set_positions(moved);
        FAIL() << "a pinned vertex moved";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("vertex 0 does not move"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(model.num_position_resets(), 0);
}

}  // namespace
}  // namespace pliant::cloth
