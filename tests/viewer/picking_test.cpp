#include "picking.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "pliant/geometry/generate.hpp"

namespace pliant::viewer {
namespace {

// Two 1 m sheets of 10 × 10 quads, at z = 0 and z = 0.5, seen from above.
struct Stack {
    geometry::TriangleMeshD mesh;
    Stack() {
        const geometry::TriangleMeshD sheet =
            geometry::convert_precision<double>(geometry::make_grid_sheet(10, 10, 1.0f, 1.0f));
        mesh = sheet;
        const auto n = static_cast<std::int32_t>(sheet.positions.size());
        for (Vec3d p : sheet.positions) {
            p.z = 0.5;
            mesh.positions.push_back(p);
        }
        for (const geometry::Triangle& t : sheet.triangles) {
            mesh.triangles.push_back({t[0] + n, t[1] + n, t[2] + n});
        }
    }
};

const render::Camera TOP = render::Camera::perspective({0.05, 0.02, 5.0}, {0.05, 0.02, 0.0},
                                                       {0.0, 1.0, 0.0}, 30.0, 200, 200);

TEST(Picking, NearestTriangleAlongTheRay) {
    const Stack stack;
    // The pixel that sees the upper sheet near its vertex at (0.1, 0.1) (not exactly on it: a ray
    // through a shared vertex may miss every triangle by rounding).
    const Vec3d seen{0.11, 0.105, 0.5};
    const render::PixelPoint pixel = TOP.project(seen);
    const TriangleHit hit =
        intersect_triangles(TOP.ray(pixel.x, pixel.y), stack.mesh.positions, stack.mesh.triangles);
    ASSERT_GE(hit.triangle, 0);
    EXPECT_GE(hit.triangle, 200);  // the upper sheet, not the lower one behind it
    EXPECT_NEAR(hit.t, norm(seen - TOP.eye()), 1e-9);
    const std::int32_t corner = nearest_corner(hit, stack.mesh.triangles);
    ASSERT_GE(corner, 0);
    EXPECT_NEAR(norm(stack.mesh.positions[static_cast<std::size_t>(corner)] - Vec3d{0.1, 0.1, 0.5}),
                0.0, 1e-6);
    // From below the same sheets are hit from their back side: the lower one first.
    const render::Camera below = render::Camera::perspective({0.05, 0.02, -5.0}, {0.05, 0.02, 0.0},
                                                             {0.0, 1.0, 0.0}, 30.0, 200, 200);
    const render::PixelPoint p2 = below.project({0.11, 0.105, 0.0});
    const TriangleHit back =
        intersect_triangles(below.ray(p2.x, p2.y), stack.mesh.positions, stack.mesh.triangles);
    ASSERT_GE(back.triangle, 0);
    EXPECT_LT(back.triangle, 200);
    // A ray beside the sheets misses.
    const render::PixelPoint outside = TOP.project({0.9, 0.0, 0.5});
    const TriangleHit miss = intersect_triangles(TOP.ray(outside.x, outside.y),
                                                 stack.mesh.positions, stack.mesh.triangles);
    EXPECT_EQ(miss.triangle, -1);
    EXPECT_EQ(nearest_corner(miss, stack.mesh.triangles), -1);
    EXPECT_EQ(intersect_triangles(TOP.ray(1.0, 1.0), {}, {}).triangle, -1);
}

TEST(Picking, DegenerateTrianglesAreNeverHit) {
    const std::vector<Vec3d> positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
    const std::vector<geometry::Triangle> triangles = {{0, 1, 2}, {0, 0, 1}};
    const render::Ray ray{{0.5, 0.0, 1.0}, {0.0, 0.0, -1.0}};
    EXPECT_EQ(intersect_triangles(ray, positions, triangles).triangle, -1);
}

TEST(Picking, PointNearestToTheCameraWithinTheRadius) {
    const std::vector<Vec3f> points = {
        {0.1f, 0.1f, 0.0f},  // 0: under the cursor, far
        {0.1f, 0.1f, 0.5f},  // 1: under the cursor, nearer
        {0.3f, 0.3f, 0.9f},  // 2: nearest, but away from the cursor
        {0.1f, 0.1f, 6.0f},  // 3: behind the camera
    };
    const render::PixelPoint cursor = TOP.project({0.1, 0.1, 0.5});
    EXPECT_EQ(pick_point(TOP, points, cursor.x, cursor.y, 3.0), 1);
    // Clipping away z > 0.25 (keep (p − (0, 0, 0.25)) · (0, 0, −1) ≥ 0) leaves point 0.
    const render::ClipPlane keep_low{{0.0, 0.0, 0.25}, {0.0, 0.0, -1.0}};
    EXPECT_EQ(pick_point(TOP, points, cursor.x, cursor.y, 3.0, keep_low), 0);
    EXPECT_EQ(pick_point(TOP, points, 0.0, 0.0, 3.0), -1);
    EXPECT_EQ(pick_point(TOP, {}, cursor.x, cursor.y, 3.0), -1);
}

TEST(Picking, DragTargetStaysAtTheAnchorsDepthUnderTheCursor) {
    const render::Camera oblique = render::Camera::perspective({3.0, -2.0, 2.5}, {0.0, 0.0, 0.0},
                                                               {0.0, 0.0, 1.0}, 40.0, 320, 240);
    const Vec3d anchor{0.2, -0.1, 0.3};
    for (const auto& [x, y] :
         {std::pair{10.5, 20.25}, std::pair{160.0, 120.0}, std::pair{300.0, 230.0}}) {
        const Vec3d target = drag_target(oblique, x, y, anchor);
        const render::PixelPoint p = oblique.project(target);
        EXPECT_NEAR(p.x, x, 1e-9);
        EXPECT_NEAR(p.y, y, 1e-9);
        EXPECT_NEAR(dot(target - anchor, oblique.forward()), 0.0, 1e-12);
    }
    const render::PixelPoint a = oblique.project(anchor);
    EXPECT_NEAR(norm(drag_target(oblique, a.x, a.y, anchor) - anchor), 0.0, 1e-12);
}

}  // namespace
}  // namespace pliant::viewer
