#include "pliant/geometry/generate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <utility>

#include "pliant/core/error.hpp"
#include "pliant/geometry/topology.hpp"
#include "pliant/geometry/validate.hpp"

namespace pliant::geometry {
namespace {

TEST(Generate, GridSheetCountsAndExtent) {
    const TriangleMesh mesh = make_grid_sheet(134, 134, 2.0f, 2.0f);
    EXPECT_EQ(mesh.num_triangles(), 35912u);  // the drape scene of DESIGN.md
    EXPECT_EQ(mesh.num_vertices(), 135u * 135u);
    for (const Vec3f& p : mesh.positions) {
        ASSERT_LE(std::abs(p.x), 1.0f);
        ASSERT_LE(std::abs(p.y), 1.0f);
        ASSERT_EQ(p.z, 0.0f);
    }
    // Counter-clockwise seen from +z: every normal points up.
    for (const Triangle& t : mesh.triangles) {
        const Vec3f n = cross(mesh.positions[static_cast<std::size_t>(t[1])] -
                                  mesh.positions[static_cast<std::size_t>(t[0])],
                              mesh.positions[static_cast<std::size_t>(t[2])] -
                                  mesh.positions[static_cast<std::size_t>(t[0])]);
        ASSERT_GT(n.z, 0.0f);
    }
    EXPECT_THROW(make_grid_sheet(0, 3, 1.0f, 1.0f), InvalidInput);
    EXPECT_THROW(make_grid_sheet(3, 3, -1.0f, 1.0f), InvalidInput);
}

TEST(Generate, NearestSquareSheetsForThePapersSizes) {
    EXPECT_EQ(nearest_square_sheet(2244), 33);
    EXPECT_EQ(nearest_square_sheet(27030), 116);
    EXPECT_EQ(nearest_square_sheet(35992), 134);
    EXPECT_EQ(nearest_square_sheet(1), 1);
}

TEST(Generate, AccordionFoldIsIsometricAndLayered) {
    TriangleMesh mesh = make_grid_sheet(120, 10, 3.0f, 0.25f);
    const MeshTopology topo = build_topology(mesh.triangles, mesh.num_vertices());
    std::vector<float> rest;
    for (const Edge& e : topo.edges) {
        rest.push_back(norm(mesh.positions[static_cast<std::size_t>(e[0])] -
                            mesh.positions[static_cast<std::size_t>(e[1])]));
    }
    const float gap = 0.05f;
    fold_accordion(mesh.positions, 0.5f, gap);
    float z_max = 0.0f;
    for (std::size_t e = 0; e < topo.edges.size(); ++e) {
        const float len = norm(mesh.positions[static_cast<std::size_t>(topo.edges[e][0])] -
                               mesh.positions[static_cast<std::size_t>(topo.edges[e][1])]);
        // Chords of the fold arcs are slightly shorter than the arc: at most a few percent here.
        ASSERT_NEAR(len, rest[e], 0.05f * rest[e]);
    }
    for (const Vec3f& p : mesh.positions) {
        z_max = std::max(z_max, p.z);
        ASSERT_GE(p.x, -0.5f * gap - 1e-5f);
        ASSERT_LE(p.x, 0.5f + 0.5f * gap + 1e-5f);
    }
    // 3 m of sheet in periods of 0.5 + π·0.025 m: 5 folds, so the top layer is 5 gaps up.
    EXPECT_NEAR(z_max, 5 * gap, 1e-4f);
}

// Closed and consistently oriented: every edge has exactly two triangles that traverse it in
// opposite directions. Returns the signed volume (positive when the triangles face outwards).
double check_closed_oriented(const TriangleMeshD& mesh) {
    validate_mesh(mesh, "generated");
    const MeshTopology topo = build_topology(mesh.triangles, mesh.num_vertices());
    for (std::size_t e = 0; e < topo.num_edges(); ++e) {
        EXPECT_EQ(topo.triangles_of_edge(static_cast<std::int32_t>(e)).size(), 2u) << "edge " << e;
    }
    std::set<std::pair<std::int32_t, std::int32_t>> directed;
    double volume = 0.0;
    for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
            EXPECT_TRUE(directed.insert({t[k], t[(k + 1) % 3]}).second) << "directed edge twice";
        }
        const Vec3d a = mesh.positions[static_cast<std::size_t>(t[0])];
        const Vec3d b = mesh.positions[static_cast<std::size_t>(t[1])];
        const Vec3d c = mesh.positions[static_cast<std::size_t>(t[2])];
        volume += dot(a, cross(b, c)) / 6.0;
    }
    return volume;
}

// Every face's normal points away from `inside` (true for convex shapes around it).
void check_faces_point_away(const TriangleMeshD& mesh, Vec3d inside) {
    for (const Triangle& t : mesh.triangles) {
        const Vec3d a = mesh.positions[static_cast<std::size_t>(t[0])];
        const Vec3d b = mesh.positions[static_cast<std::size_t>(t[1])];
        const Vec3d c = mesh.positions[static_cast<std::size_t>(t[2])];
        const Vec3d n = cross(b - a, c - a);
        ASSERT_GT(norm(n), 0.0);
        ASSERT_GT(dot(n, (a + b + c) / 3.0 - inside), 0.0);
    }
}

TEST(Generate, UvSphereIsClosedOutwardAndOnTheSphere) {
    for (const int segments : {3, 4, 7, 48}) {
        const Vec3d centre{0.5, -1.0, 2.0};
        const TriangleMeshD s = make_uv_sphere(centre, 0.75, segments);
        const int stacks = std::max(2, segments / 2);
        EXPECT_EQ(s.num_vertices(), static_cast<std::size_t>(2 + (stacks - 1) * segments));
        EXPECT_EQ(s.num_triangles(), static_cast<std::size_t>(2 * segments * (stacks - 1)));
        for (const Vec3d& p : s.positions) {
            ASSERT_NEAR(norm(p - centre), 0.75, 1e-12);
        }
        const double volume = check_closed_oriented(s);
        EXPECT_GT(volume, 0.0);
        EXPECT_LT(volume, 4.0 / 3.0 * std::numbers::pi * 0.75 * 0.75 * 0.75);
        check_faces_point_away(s, centre);
        if (segments == 48) {  // a fine sphere is close to the real volume
            EXPECT_NEAR(volume, 4.0 / 3.0 * std::numbers::pi * 0.421875, 0.02);
        }
    }
    EXPECT_THROW(make_uv_sphere({0, 0, 0}, 1.0, 2), InvalidInput);
    EXPECT_THROW(make_uv_sphere({0, 0, 0}, 0.0, 8), InvalidInput);
    EXPECT_THROW(make_uv_sphere({0, NAN, 0}, 1.0, 8), InvalidInput);
}

TEST(Generate, BoxIsClosedOutwardWithTheRightVolume) {
    const TriangleMeshD box = make_box({-1, 0, 2}, {1, 0.5, 5});
    EXPECT_EQ(box.num_vertices(), 8u);
    EXPECT_EQ(box.num_triangles(), 12u);
    EXPECT_NEAR(check_closed_oriented(box), 2.0 * 0.5 * 3.0, 1e-12);
    check_faces_point_away(box, {0, 0.25, 3.5});
    EXPECT_THROW(make_box({0, 0, 0}, {1, 0, 1}), InvalidInput);
    EXPECT_THROW(make_box({0, 0, 0}, {1, INFINITY, 1}), InvalidInput);
}

TEST(Generate, PlaneSquareFacesItsNormal) {
    for (const Vec3d normal : {Vec3d{0, 0, 1}, Vec3d{0, 0, -2}, Vec3d{1, 2, 3}, Vec3d{-1, 0, 0}}) {
        const Vec3d point{0.25, -3, 1};
        const TriangleMeshD sq = make_plane_square(point, normal, 2.0);
        ASSERT_EQ(sq.num_vertices(), 4u);
        ASSERT_EQ(sq.num_triangles(), 2u);
        const Vec3d unit = normal / norm(normal);
        Vec3d centroid{};
        for (const Vec3d& p : sq.positions) {
            EXPECT_NEAR(dot(p - point, unit), 0.0, 1e-12);              // in the plane
            EXPECT_NEAR(norm(p - point), 2.0 * std::sqrt(2.0), 1e-12);  // corners of the square
            centroid += p / 4.0;
        }
        EXPECT_NEAR(norm(centroid - point), 0.0, 1e-12);
        EXPECT_NEAR(norm(sq.positions[1] - sq.positions[0]), 4.0, 1e-12);
        for (const Triangle& t : sq.triangles) {
            const Vec3d n = cross(sq.positions[static_cast<std::size_t>(t[1])] -
                                      sq.positions[static_cast<std::size_t>(t[0])],
                                  sq.positions[static_cast<std::size_t>(t[2])] -
                                      sq.positions[static_cast<std::size_t>(t[0])]);
            EXPECT_NEAR(dot(n / norm(n), unit), 1.0, 1e-12);
        }
    }
    EXPECT_THROW(make_plane_square({0, 0, 0}, {0, 0, 0}, 1.0), InvalidInput);
    EXPECT_THROW(make_plane_square({0, 0, 0}, {0, 0, 1}, -1.0), InvalidInput);
}

}  // namespace
}  // namespace pliant::geometry
