#include "pliant/geometry/topology.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "pliant/geometry/generate.hpp"
#include "support/random_meshes.hpp"

namespace pliant::geometry {
namespace {

// Independent reference: unique edges through std::set, incidence by scanning all triangles.
void expect_matches_reference(const TriangleMesh& mesh) {
    const MeshTopology topo = build_topology(mesh.triangles, mesh.num_vertices());
    std::set<Edge> reference;
    for (const Triangle& t : mesh.triangles) {
        for (int k = 0; k < 3; ++k) {
            reference.insert({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])});
        }
    }
    ASSERT_EQ(topo.edges, std::vector<Edge>(reference.begin(), reference.end()));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            const Edge e = topo.edges[static_cast<std::size_t>(topo.triangle_edges[t][k])];
            const std::int32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
            EXPECT_EQ(e, (Edge{std::min(a, b), std::max(a, b)}));
        }
    }
    for (std::size_t e = 0; e < topo.edges.size(); ++e) {
        std::vector<std::int32_t> expected;
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const auto& tri = mesh.triangles[t];
            const bool has_a = std::count(tri.begin(), tri.end(), topo.edges[e][0]) > 0;
            const bool has_b = std::count(tri.begin(), tri.end(), topo.edges[e][1]) > 0;
            if (has_a && has_b) {
                expected.push_back(static_cast<std::int32_t>(t));
            }
        }
        const auto got = topo.triangles_of_edge(static_cast<std::int32_t>(e));
        EXPECT_EQ(std::vector<std::int32_t>(got.begin(), got.end()), expected);
    }
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        std::vector<std::int32_t> expected;
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            const auto& tri = mesh.triangles[t];
            if (std::count(tri.begin(), tri.end(), static_cast<std::int32_t>(v)) > 0) {
                expected.push_back(static_cast<std::int32_t>(t));
            }
        }
        const auto got = topo.triangles_of_vertex(static_cast<std::int32_t>(v));
        EXPECT_EQ(std::vector<std::int32_t>(got.begin(), got.end()), expected);
    }
}

TEST(Topology, GridSheetSatisfiesEulerAndMatchesReference) {
    const TriangleMesh mesh = make_grid_sheet(7, 5, 1.0f, 1.0f);
    const MeshTopology topo = build_topology(mesh.triangles, mesh.num_vertices());
    // A disk: V - E + F = 1.
    EXPECT_EQ(static_cast<std::int64_t>(mesh.num_vertices()) -
                  static_cast<std::int64_t>(topo.num_edges()) +
                  static_cast<std::int64_t>(mesh.num_triangles()),
              1);
    std::size_t boundary = 0;
    for (std::size_t e = 0; e < topo.num_edges(); ++e) {
        const auto n = topo.triangles_of_edge(static_cast<std::int32_t>(e)).size();
        ASSERT_TRUE(n == 1 || n == 2);
        boundary += n == 1 ? 1 : 0;
    }
    EXPECT_EQ(boundary, 2u * (7 + 5));
    expect_matches_reference(mesh);
}

TEST(Topology, SoupAndNonManifoldMatchReference) {
    expect_matches_reference(test::random_triangle_soup(20, 0.1f, 3));
    // Three triangles on one edge (non-manifold) plus an isolated vertex.
    TriangleMesh fan;
    fan.positions.resize(6);
    fan.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    expect_matches_reference(fan);
    const MeshTopology topo = build_topology(fan.triangles, fan.num_vertices());
    EXPECT_EQ(topo.triangles_of_edge(0).size(), 3u);
    EXPECT_TRUE(topo.triangles_of_vertex(5).empty());
}

TEST(Topology, EmptyMesh) {
    const MeshTopology topo = build_topology({}, 0);
    EXPECT_TRUE(topo.edges.empty());
    EXPECT_EQ(topo.edge_triangle_offsets.size(), 1u);
    EXPECT_EQ(topo.vertex_triangle_offsets.size(), 1u);
}

}  // namespace
}  // namespace pliant::geometry
