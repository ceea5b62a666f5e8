// Seams: pairs pulled together over their seconds, then held at the thickness; panels sewn edge
// to edge with self-collision on end closed and intersection-free; bad seams refused.
#include "pliant/cloth/seams.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "pliant/cloth/solver.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/core/error.hpp"
#include "pliant/geometry/generate.hpp"

namespace pliant::cloth {
namespace {

TEST(Seams, TargetRampsFromTheStartDistanceToTheGap) {
    const std::vector<Vec3d> x{{0, 0, 0}, {1, 0, 0}, {5, 5, 5}, {5, 5, 5.01}};
    Seams seams;
    const std::vector<std::int32_t> a{0, 2};
    const std::vector<std::int32_t> b{1, 3};
    seams.add(a, b, 2.0, 0.05, x);
    ASSERT_EQ(seams.num_pairs(), 2u);
    EXPECT_DOUBLE_EQ(seams.target(0, 0.0), 1.0);
    EXPECT_DOUBLE_EQ(seams.target(0, 1.0), 0.525);
    EXPECT_NEAR(seams.target(0, 2.0), 0.05, 1e-15);
    EXPECT_NEAR(seams.target(0, 10.0), 0.05, 1e-15);
    EXPECT_NEAR(seams.target(1, 0.0), 0.05, 1e-15);  // closer than the gap already: held there
    EXPECT_NEAR(seams.max_opening(x), 0.95, 1e-12);

    // One projection with equal masses meets in the middle; a pinned end does not move.
    std::vector<Vec3d> y = x;
    seams.project(y, std::vector<double>{1.0, 1.0, 1.0, 1.0}, 2.0);
    EXPECT_NEAR(y[0].x, 0.475, 1e-12);
    EXPECT_NEAR(y[1].x, 0.525, 1e-12);
    EXPECT_EQ(y[3], x[3]);  // pairs closer than their target are not pushed apart
    y = x;
    seams.project(y, std::vector<double>{0.0, 1.0, 1.0, 1.0}, 2.0);
    EXPECT_EQ(y[0], x[0]);
    EXPECT_NEAR(y[1].x, 0.05, 1e-12);
}

TEST(Seams, BadSeamsAreRefused) {
    const std::vector<Vec3d> x{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    Seams seams;
    const std::vector<std::int32_t> one{0};
    const std::vector<std::int32_t> two{1, 2};
    EXPECT_THROW(seams.add(one, two, 1.0, 0.0, x), InvalidInput);
    EXPECT_THROW(seams.add({}, {}, 1.0, 0.0, x), InvalidInput);
    EXPECT_THROW(seams.add(one, std::vector<std::int32_t>{3}, 1.0, 0.0, x), InvalidInput);
    EXPECT_THROW(seams.add(one, std::vector<std::int32_t>{-1}, 1.0, 0.0, x), InvalidInput);
    EXPECT_THROW(seams.add(one, one, 1.0, 0.0, x), InvalidInput);
    EXPECT_THROW(seams.add(one, std::vector<std::int32_t>{1}, 0.0, 0.0, x), InvalidInput);
    EXPECT_THROW(seams.add(one, std::vector<std::int32_t>{1}, 1.0, -1.0, x), InvalidInput);
    EXPECT_TRUE(seams.empty());
}

// Two 0.4 m panels lying 0.1 m apart in a plane, sewn along their facing edges over 0.5 s with
// self-collision on and no gravity: closed to the thickness, and never intersecting.
TEST(Seams, PanelsSewnEdgeToEdgeCloseWithoutIntersecting) {
    constexpr int N = 8;
    const geometry::TriangleMesh panel = geometry::make_grid_sheet(N, N, 0.4F, 0.4F);
    geometry::TriangleMeshD mesh;
    const auto per_panel = static_cast<std::int32_t>(panel.positions.size());
    for (int k = 0; k < 2; ++k) {
        const double shift = k == 0 ? -0.25 : 0.25;
        for (const Vec3f& p : panel.positions) {
            mesh.positions.push_back({p.x + shift, p.y, 0.0});
        }
        for (const geometry::Triangle& t : panel.triangles) {
            mesh.triangles.push_back(
                {t[0] + k * per_panel, t[1] + k * per_panel, t[2] + k * per_panel});
        }
    }
    // The left panel's right column (x = +0.2 - 0.25) to the right panel's left column.
    std::vector<std::int32_t> a;
    std::vector<std::int32_t> b;
    for (int j = 0; j <= N; ++j) {
        a.push_back(j * (N + 1) + N);
        b.push_back(per_panel + j * (N + 1));
    }
    ClothMaterial material;
    ClothSolver solver(mesh, material);
    solver.set_gravity({0.0, 0.0, 0.0});
    solver.enable_self_collision(true);
    solver.add_seam(a, b, 0.5);
    EXPECT_NEAR(solver.model().seams().max_opening(solver.positions()), 0.1 - material.thickness,
                1e-6);
    for (int frame = 0; frame < 24; ++frame) {
        solver.step(1.0 / 24.0, 20);
        ASSERT_EQ(collision::count_intersecting_pairs(solver.positions(), solver.triangles()), 0)
            << "frame " << frame;
    }
    EXPECT_LT(solver.model().seams().max_opening(solver.positions()), 1e-3);
    // Edge to edge: the sewn columns are a thickness apart and the panels still flat.
    for (const Vec3d& p : solver.positions()) {
        EXPECT_NEAR(p.z, 0.0, 1e-3);
    }
}

}  // namespace
}  // namespace pliant::cloth
