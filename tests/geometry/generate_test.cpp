#include "pliant/geometry/generate.hpp"

#include <gtest/gtest.h>

#include "pliant/core/error.hpp"
#include "pliant/geometry/topology.hpp"

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

}  // namespace
}  // namespace pliant::geometry
