#include "pliant/cloth/self_collision.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

// A 2 m sheet of 40 × 40 quads dropped from 1.2 m onto a sphere of radius 0.5 m: its corners
// swing down and fold through each other around frame 17 unless self-collision stops them.
// Returns the exact count of intersecting non-adjacent triangle pairs after every frame.
std::vector<std::int64_t> drop_on_sphere(bool self_collision, int frames) {
    geometry::TriangleMeshD mesh =
        geometry::convert_precision<double>(geometry::make_grid_sheet(40, 40, 2.0f, 2.0f));
    for (Vec3d& p : mesh.positions) {
        p.z = 1.2;
    }
    ClothSolver solver(mesh, ClothMaterial{});
    solver.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.5});
    solver.enable_self_collision(self_collision);
    std::vector<std::int64_t> counts;
    for (int f = 0; f < frames; ++f) {
        const ClothStepStats stats = solver.step(1.0 / 24.0, 20);
        EXPECT_EQ(stats.has_self_collision, self_collision);
        counts.push_back(
            collision::count_intersecting_pairs(solver.positions(), solver.triangles()));
    }
    return counts;
}

TEST(SelfCollision, NoFrameIntersectsWhereThePlainSolverDoes) {
    constexpr int FRAMES = 20;
    const std::vector<std::int64_t> without = drop_on_sphere(false, FRAMES);
    std::int64_t worst = 0;
    for (const std::int64_t count : without) {
        worst = std::max(worst, count);
    }
    EXPECT_GT(worst, 0) << "the scene no longer folds through itself: the test proves nothing";
    const std::vector<std::int64_t> with = drop_on_sphere(true, FRAMES);
    for (int f = 0; f < FRAMES; ++f) {
        EXPECT_EQ(with[static_cast<std::size_t>(f)], 0) << "frame " << f + 1;
    }
}

TEST(SelfCollision, FailSafeRevertsAPairMovingThroughEachOther) {
    // Two separate triangles; the top one is moved straight through the bottom one in one step
    // without any proximity handling: the fail-safe must put its vertices back.
    const std::vector<geometry::Triangle> triangles{{0, 1, 2}, {3, 4, 5}};
    const std::vector<Vec3d> start{{0, 0, 0},       {1, 0, 0},       {0, 1, 0},
                                   {0.2, 0.2, 0.5}, {0.6, 0.2, 0.5}, {0.2, 0.6, 0.5}};
    std::vector<Vec3d> end = start;
    for (int v = 3; v < 6; ++v) {
        end[static_cast<std::size_t>(v)].z = -0.5;
    }
    std::vector<Vec3d> velocities(6, Vec3d{0.0, 0.0, -12.0});
    SelfCollision self(triangles, 6, 0.01);
    self.enforce(start, end, velocities);
    EXPECT_GT(self.stats().ccd_hits, 0);
    EXPECT_EQ(collision::count_intersecting_pairs(end, triangles), 0);
    for (int v = 3; v < 6; ++v) {
        EXPECT_EQ(end[static_cast<std::size_t>(v)], start[static_cast<std::size_t>(v)]);
        EXPECT_EQ(velocities[static_cast<std::size_t>(v)], (Vec3d{0.0, 0.0, 0.0}));
    }
}

}  // namespace
}  // namespace pliant::cloth
