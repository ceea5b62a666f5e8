#include "pliant/cloth/obstacles.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

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

// push_out on a sphere skips the exact distance far from it: the same depth and the same bits of
// x as the exact test, at the edge of the reach (the thickness away, within a few 1e-9) and far.
TEST(Obstacles, SpherePushOutIsTheExactTestAtTheEdgeOfItsReach) {
    const SphereObstacle sphere{{0.1, -0.2, 0.3}, 0.5};
    const double thickness = 0.005;
    std::mt19937_64 random(3);
    std::normal_distribution<double> gaussian;
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    int touching = 0;
    int apart = 0;
    for (int i = 0; i < 20000; ++i) {
        Vec3d direction{gaussian(random), gaussian(random), gaussian(random)};
        direction = direction * (1.0 / norm(direction));
        // Distances from the centre around radius + thickness: within 5e-9 relative, or far.
        const double scale =
            i % 4 == 0 ? 1.0 + 0.5 * uniform(random) : 1.0 + 5e-9 * uniform(random);
        const Vec3d start = sphere.center + direction * ((sphere.radius + thickness) * scale);
        Vec3d x = start;
        const ContactCorrection contact = push_out(sphere, x, thickness);
        // The exact test: surface_distance, then the move along its normal.
        const SurfaceDistance surface = surface_distance(sphere, start);
        const double depth = thickness - surface.distance;
        Vec3d expected = start;
        if (depth > 0.0) {
            expected += surface.normal * depth;
            ++touching;
        } else {
            ++apart;
        }
        ASSERT_EQ(contact.depth, depth > 0.0 ? depth : 0.0) << i;
        ASSERT_EQ(std::memcmp(&x, &expected, sizeof(Vec3d)), 0) << i;
    }
    EXPECT_GT(touching, 5000);
    EXPECT_GT(apart, 5000);
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
