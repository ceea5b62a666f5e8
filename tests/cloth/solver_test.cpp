#include "pliant/cloth/solver.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

// A square sheet of n × n quads, side `size` metres, at height z.
geometry::TriangleMeshD sheet(int n, double size, double z) {
    const geometry::TriangleMesh flat =
        geometry::make_grid_sheet(n, n, static_cast<float>(size), static_cast<float>(size));
    geometry::TriangleMeshD mesh = geometry::convert_precision<double>(flat);
    for (Vec3d& p : mesh.positions) {
        p.z = z;
    }
    return mesh;
}

double max_edge_strain(const ClothSolver& solver, const geometry::TriangleMeshD& rest) {
    double worst = 0.0;
    for (const geometry::Triangle& t : rest.triangles) {
        for (int k = 0; k < 3; ++k) {
            const auto a = static_cast<std::size_t>(t[static_cast<std::size_t>(k)]);
            const auto b = static_cast<std::size_t>(t[static_cast<std::size_t>((k + 1) % 3)]);
            const double rest_length = norm(rest.positions[a] - rest.positions[b]);
            const double length = norm(solver.positions()[a] - solver.positions()[b]);
            worst = std::max(worst, std::fabs(length / rest_length - 1.0));
        }
    }
    return worst;
}

TEST(ClothSolver, FreeFallFollowsTheSubstepIntegrator) {
    // No damping, nothing to hit: every vertex falls as symplectic Euler with step h predicts,
    // x(n h) = x0 + g h² n (n + 1) / 2, and the constraints stay satisfied.
    ClothMaterial material;
    material.damping = 0.0;
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 2.0);
    ClothSolver solver(mesh, material);
    const int substeps = 10;
    const int frames = 5;
    for (int f = 0; f < frames; ++f) {
        solver.step(0.04, substeps);
    }
    const double h = 0.04 / substeps;
    const double n = frames * substeps;
    const double expected = 2.0 - 9.81 * h * h * n * (n + 1.0) / 2.0;
    for (const Vec3d& p : solver.positions()) {
        EXPECT_NEAR(p.z, expected, 1e-9);
    }
    EXPECT_LT(max_edge_strain(solver, mesh), 1e-9);
}

TEST(ClothSolver, PinnedSheetHangsWithoutStretchingAndComesToRest) {
    // 1 m sheet pinned along one edge (y = +0.5), hanging for 3 s.
    const geometry::TriangleMeshD mesh = sheet(16, 1.0, 1.0);
    std::vector<std::int32_t> pinned;
    for (std::int32_t v = 0; v < static_cast<std::int32_t>(mesh.positions.size()); ++v) {
        if (mesh.positions[static_cast<std::size_t>(v)].y > 0.499) {
            pinned.push_back(v);
        }
    }
    ASSERT_EQ(pinned.size(), 17u);
    ClothMaterial material;
    material.damping = 5.0;
    ClothSolver solver(mesh, material, pinned);
    for (int f = 0; f < 72; ++f) {
        solver.step(1.0 / 24.0, 20);
    }
    for (const std::int32_t v : pinned) {
        EXPECT_EQ(solver.positions()[static_cast<std::size_t>(v)],
                  mesh.positions[static_cast<std::size_t>(v)]);
    }
    double lowest = std::numeric_limits<double>::infinity();
    double fastest = 0.0;
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        ASSERT_TRUE(std::isfinite(solver.positions()[v].z));
        lowest = std::min(lowest, solver.positions()[v].z);
        fastest = std::max(fastest, norm(solver.velocities()[v]));
    }
    EXPECT_LT(lowest, 0.1);    // it hangs down by about its length
    EXPECT_GT(lowest, -0.05);  // and not further
    EXPECT_LT(fastest, 0.05);  // at rest
    EXPECT_LT(max_edge_strain(solver, mesh), 0.02);
}

TEST(ClothSolver, DrapesOverASphereAndKeepsTheThickness) {
    // A 1.2 m sheet dropped 0.3 m onto a sphere of radius 0.3 m, then onto the ground.
    const geometry::TriangleMeshD mesh = sheet(24, 1.2, 0.6);
    ClothMaterial material;
    ClothSolver solver(mesh, material);
    const SphereObstacle sphere{{0.0, 0.0, 0.0}, 0.3};
    solver.add_obstacle(sphere);
    solver.add_obstacle(PlaneObstacle{{0.0, 0.0, -0.3}, {0.0, 0.0, 1.0}});
    ClothStepStats stats;
    for (int f = 0; f < 48; ++f) {
        stats = solver.step(1.0 / 24.0, 40);
    }
    EXPECT_GT(stats.obstacle_contacts, 0);
    const double margin = material.thickness * (1.0 - 1e-9);
    for (const Vec3d& p : solver.positions()) {
        EXPECT_GE(norm(p - sphere.center) - sphere.radius, margin);
        EXPECT_GE(p.z + 0.3, margin);
    }
    // The centre vertex rests on top of the sphere.
    const Vec3d& centre = solver.positions()[mesh.positions.size() / 2];
    EXPECT_NEAR(centre.z, sphere.radius + material.thickness, 0.01);
    // One constraint iteration per substep: the stretch converges with the substep count
    // (solver.hpp), hence 40 substeps here.
    EXPECT_LT(max_edge_strain(solver, mesh), 0.07);
}

TEST(ClothSolver, BitwiseIdenticalForOneAndTwoThreads) {
    const geometry::TriangleMeshD mesh = sheet(20, 1.0, 0.5);
    const auto run = [&](int threads) {
        set_num_threads(threads);
        ClothSolver solver(mesh, ClothMaterial{});
        solver.add_obstacle(SphereObstacle{{0.1, 0.0, 0.0}, 0.25});
        for (int f = 0; f < 12; ++f) {
            solver.step(1.0 / 24.0, 10);
        }
        set_num_threads(0);
        return std::vector<Vec3d>(solver.positions().begin(), solver.positions().end());
    };
    EXPECT_EQ(run(1), run(2));
}

TEST(ClothSolver, RejectsBadInput) {
    const geometry::TriangleMeshD mesh = sheet(2, 1.0, 0.0);
    ClothMaterial negative;
    negative.areal_density = -1.0;
    EXPECT_THROW(ClothSolver(mesh, negative), InvalidInput);
    ClothMaterial nan_thickness;
    nan_thickness.thickness = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ClothSolver(mesh, nan_thickness), InvalidInput);
    const std::vector<std::int32_t> bad_pin{100};
    EXPECT_THROW(ClothSolver(mesh, ClothMaterial{}, bad_pin), InvalidInput);
    geometry::TriangleMeshD nan_mesh = mesh;
    nan_mesh.positions[0].x = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ClothSolver(nan_mesh, ClothMaterial{}), InvalidInput);
    ClothSolver solver(mesh, ClothMaterial{});
    EXPECT_THROW(solver.step(0.0, 10), InvalidInput);
    EXPECT_THROW(solver.step(0.01, 0), InvalidInput);
    EXPECT_THROW(solver.add_obstacle(SphereObstacle{{0.0, 0.0, 0.0}, -1.0}), InvalidInput);
}

TEST(ClothSolver, EverythingPinnedStaysPutAndHugeStepsStayFinite) {
    const geometry::TriangleMeshD mesh = sheet(4, 1.0, 0.0);
    std::vector<std::int32_t> all(mesh.positions.size());
    for (std::size_t v = 0; v < all.size(); ++v) {
        all[v] = static_cast<std::int32_t>(v);
    }
    ClothSolver pinned(mesh, ClothMaterial{}, all);
    pinned.step(10.0, 1);
    EXPECT_EQ(std::vector<Vec3d>(pinned.positions().begin(), pinned.positions().end()),
              mesh.positions);
    // One 10-second substep onto a sphere: no NaN.
    ClothSolver free(mesh, ClothMaterial{});
    free.add_obstacle(SphereObstacle{{0.0, 0.0, -1.0}, 0.5});
    free.step(10.0, 1);
    for (const Vec3d& p : free.positions()) {
        EXPECT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    }
}

}  // namespace
}  // namespace pliant::cloth
