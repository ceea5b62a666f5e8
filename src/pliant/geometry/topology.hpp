// MeshTopology: unique edges and incidence of a triangle mesh, in compressed-row (CSR) form.
//
// edges: #E unique undirected edges {a, b} with a < b, sorted by (a, b).
// triangle_edges[t][k]: the edge between corners k and (k+1) % 3 of triangle t.
// edge_triangles[edge_triangle_offsets[e] .. edge_triangle_offsets[e+1]): triangles incident to e,
//   ascending (1 on a boundary, 2 inside a manifold, more on non-manifold edges).
// vertex_triangles[vertex_triangle_offsets[v] .. offsets[v+1]): triangles incident to v, ascending.
//
// Built in O(T log T)-free linear passes plus one radix sort; deterministic.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::geometry {

struct MeshTopology {
    std::vector<Edge> edges;
    std::vector<std::array<std::int32_t, 3>> triangle_edges;
    std::vector<std::int32_t> edge_triangle_offsets;
    std::vector<std::int32_t> edge_triangles;
    std::vector<std::int32_t> vertex_triangle_offsets;
    std::vector<std::int32_t> vertex_triangles;

    std::size_t num_edges() const { return edges.size(); }
    std::span<const std::int32_t> triangles_of_edge(std::int32_t e) const {
        return std::span(edge_triangles)
            .subspan(
                static_cast<std::size_t>(edge_triangle_offsets[static_cast<std::size_t>(e)]),
                static_cast<std::size_t>(edge_triangle_offsets[static_cast<std::size_t>(e) + 1] -
                                         edge_triangle_offsets[static_cast<std::size_t>(e)]));
    }
    std::span<const std::int32_t> triangles_of_vertex(std::int32_t v) const {
        return std::span(vertex_triangles)
            .subspan(
                static_cast<std::size_t>(vertex_triangle_offsets[static_cast<std::size_t>(v)]),
                static_cast<std::size_t>(vertex_triangle_offsets[static_cast<std::size_t>(v) + 1] -
                                         vertex_triangle_offsets[static_cast<std::size_t>(v)]));
    }
};

// Precondition: triangles validated against num_vertices (validate_triangles).
MeshTopology build_topology(std::span<const Triangle> triangles, std::size_t num_vertices);

}  // namespace pliant::geometry
