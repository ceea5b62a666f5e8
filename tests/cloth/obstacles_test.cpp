#include "pliant/cloth/obstacles.hpp"

#include <gtest/gtest.h>

namespace pliant::cloth {
namespace {

TEST(Obstacles, SignedDistances) {
    const SurfaceDistance plane =
        surface_distance(PlaneObstacle{{0.0, 0.0, 1.0}, {0.0, 0.0, 2.0}}, {3.0, 4.0, 0.5});
    EXPECT_DOUBLE_EQ(plane.distance, -0.5);
    EXPECT_DOUBLE_EQ(plane.normal.z, 1.0);
    const SurfaceDistance sphere =
        surface_distance(SphereObstacle{{1.0, 0.0, 0.0}, 0.5}, {1.0, 2.0, 0.0});
    EXPECT_DOUBLE_EQ(sphere.distance, 1.5);
    EXPECT_DOUBLE_EQ(sphere.normal.y, 1.0);
    const BoxObstacle box{{0.0, 0.0, 0.0}, {1.0, 2.0, 3.0}};
    const SurfaceDistance inside = surface_distance(box, {0.9, 1.0, 1.5});
    EXPECT_NEAR(inside.distance, -0.1, 1e-15);
    EXPECT_DOUBLE_EQ(inside.normal.x, 1.0);
    const SurfaceDistance corner = surface_distance(box, {2.0, 3.0, 3.0});
    EXPECT_NEAR(corner.distance, std::sqrt(2.0), 1e-15);
}

TEST(Obstacles, PushOutToThickness) {
    const Obstacle ground = PlaneObstacle{};
    Vec3d x{0.3, 0.0, -0.01};
    const ContactCorrection contact = push_out(ground, x, 0.005);
    EXPECT_DOUBLE_EQ(contact.depth, 0.015);
    EXPECT_DOUBLE_EQ(contact.normal.z, 1.0);
    EXPECT_DOUBLE_EQ(x.z, 0.005);
    EXPECT_DOUBLE_EQ(x.x, 0.3);
    Vec3d above{0.0, 0.0, 1.0};
    EXPECT_EQ(push_out(ground, above, 0.005).depth, 0.0);
    EXPECT_DOUBLE_EQ(above.z, 1.0);
    // Out of a sphere radially.
    Vec3d inside{0.0, 0.2, 0.0};
    push_out(SphereObstacle{{0.0, 0.0, 0.0}, 0.5}, inside, 0.01);
    EXPECT_NEAR(inside.y, 0.51, 1e-15);
}

TEST(Obstacles, CoulombFrictionSticksOrSlows) {
    const Vec3d up{0.0, 0.0, 1.0};
    // Slow slide, strong normal correction: sticks (only the normal part is kept).
    const Vec3d stuck = apply_friction({0.1, 0.0, 0.2}, up, 1.0, 0.5, 0.3);
    EXPECT_DOUBLE_EQ(stuck.x, 0.0);
    EXPECT_DOUBLE_EQ(stuck.z, 0.2);
    // Fast slide: slowed by kinetic · normal speed.
    const Vec3d sliding = apply_friction({2.0, 0.0, 0.0}, up, 1.0, 0.5, 0.3);
    EXPECT_NEAR(sliding.x, 2.0 - 0.3, 1e-15);
    // Kinetic friction never reverses the motion.
    const Vec3d stopped = apply_friction({1.0, 0.0, 0.0}, up, 10.0, 0.0, 1.0);
    EXPECT_DOUBLE_EQ(stopped.x, 0.0);
    // No normal correction: no friction.
    const Vec3d free = apply_friction({1.0, 0.0, 0.0}, up, 0.0, 0.5, 0.3);
    EXPECT_DOUBLE_EQ(free.x, 1.0);
}

}  // namespace
}  // namespace pliant::cloth
