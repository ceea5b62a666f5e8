#include "pliant/cloth/self_collision.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

// A 2 m sheet of 40 × 40 quads dropped from 1.2 m onto a sphere of radius 0.5 m, its stretch
// solved edge by edge: it stretches, and its corners swing down and fold through each other
// around frame 17 unless self-collision stops them (with stretch chains, the default, it keeps
// its length and does not fold through itself in 48 frames). Returns the exact count of
// intersecting non-adjacent triangle pairs after every frame.
std::vector<std::int64_t> drop_on_sphere(bool self_collision, int frames) {
    geometry::TriangleMeshD mesh =
        geometry::convert_precision<double>(geometry::make_grid_sheet(40, 40, 2.0f, 2.0f));
    for (Vec3d& p : mesh.positions) {
        p.z = 1.2;
    }
    ClothMaterial single_edges;
    single_edges.stretch_solver = StretchSolver::edges;
    ClothSolver solver(mesh, single_edges);
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

TEST(SelfCollision, RandomViolentMotionNeverIntersects) {
    // A crumpled sheet thrown together by random velocities (several m/s per vertex, with 4
    // substeps per frame several times the thickness per substep): paths fail all the time,
    // vertices escape, pairs are searched again and the fail-safe reverts; every frame must stay
    // intersection-free.
    geometry::TriangleMeshD mesh =
        geometry::convert_precision<double>(geometry::make_grid_sheet(16, 16, 0.4f, 0.4f));
    for (Vec3d& p : mesh.positions) {
        p.z = 0.5 + 0.05 * std::sin(20.0 * p.x) * std::cos(17.0 * p.y);
    }
    ClothSolver solver(mesh, ClothMaterial{});
    solver.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
    solver.enable_self_collision(true);
    ASSERT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()), 0);
    std::int64_t hits = 0;
    std::int64_t searched = 0;
    for (int f = 0; f < 8; ++f) {
        const ClothStepStats stats = solver.step(1.0 / 24.0, 4);
        hits += stats.self.ccd_hits;
        searched += stats.self.new_paths;
        ASSERT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()), 0)
            << "frame " << f + 1;
        if (f % 3 == 0) {
            // Kick: random velocities towards and away from the middle, folding the sheet.
            std::mt19937_64 random(static_cast<std::uint64_t>(f));
            std::uniform_real_distribution<double> uniform(-1.0, 1.0);
            std::vector<Vec3d> kicked(solver.velocities().begin(), solver.velocities().end());
            for (std::size_t v = 0; v < kicked.size(); ++v) {
                const Vec3d& p = solver.positions()[v];
                kicked[v] = Vec3d{-10.0 * p.x, -10.0 * p.y, 3.0 * uniform(random)} +
                            Vec3d{uniform(random), uniform(random), uniform(random)} * 2.0;
            }
            solver.set_velocities(kicked);
        }
    }
    EXPECT_GT(searched, 0) << "no path was ever renewed: the test proves nothing";
    EXPECT_GT(hits, 0) << "the fail-safe never had to act: the test proves nothing";
}

TEST(SelfCollision, StackedSheetsLandAThicknessApart) {
    // Two sheets 15 mm apart fall onto the ground, the upper one onto the lower: slow, coherent
    // motion in which paths hold for many windows, so every contact has to come from the
    // candidates. The upper sheet must end a thickness above the lower one, nowhere through it.
    const geometry::TriangleMeshD sheet =
        geometry::convert_precision<double>(geometry::make_grid_sheet(12, 12, 0.3f, 0.3f));
    geometry::TriangleMeshD mesh;
    for (int layer = 0; layer < 2; ++layer) {
        const auto offset = static_cast<std::int32_t>(mesh.positions.size());
        for (Vec3d p : sheet.positions) {
            p.z = 0.02 + 0.015 * layer;
            p.x += 0.01 * layer;  // vertices of one layer above faces of the other
            mesh.positions.push_back(p);
        }
        for (const geometry::Triangle& t : sheet.triangles) {
            mesh.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
        }
    }
    ClothMaterial material;
    ClothSolver solver(mesh, material);
    solver.add_obstacle(PlaneObstacle{{0.0, 0.0, 0.0}, {0.0, 0.0, 1.0}});
    solver.enable_self_collision(true);
    for (int f = 0; f < 24; ++f) {
        solver.step(1.0 / 24.0, 20);
        ASSERT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()), 0)
            << "frame " << f + 1;
    }
    const std::size_t n = sheet.positions.size();
    double lowest_gap = 1.0;
    for (std::size_t v = 0; v < n; ++v) {
        lowest_gap = std::min(lowest_gap, solver.positions()[n + v].z - solver.positions()[v].z);
    }
    // Both rest: the lower at the thickness above the ground, the upper a thickness above it.
    EXPECT_NEAR(solver.positions()[n / 2].z, material.thickness, 1e-3);
    EXPECT_GT(lowest_gap, 0.9 * material.thickness);
    EXPECT_LT(lowest_gap, 1.5 * material.thickness);
}

TEST(SelfCollision, BitwiseIdenticalForOneAndTwoThreads) {
    const auto run = [](int threads) {
        set_num_threads(threads);
        geometry::TriangleMeshD mesh =
            geometry::convert_precision<double>(geometry::make_grid_sheet(30, 30, 1.5f, 1.5f));
        for (Vec3d& p : mesh.positions) {
            p.z = 0.8;
        }
        ClothSolver solver(mesh, ClothMaterial{});
        solver.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, 0.4});
        solver.enable_self_collision(true);
        for (int f = 0; f < 18; ++f) {
            solver.step(1.0 / 24.0, 20);
        }
        set_num_threads(0);
        return std::vector<Vec3d>(solver.positions().begin(), solver.positions().end());
    };
    EXPECT_EQ(run(1), run(2));
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
