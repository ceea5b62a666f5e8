// Representative Triangles (Curtis, Tamstorf, Manocha 2008, "Fast Collision Detection for
// Deformable Models using Representative-Triangles"): every vertex and every edge of a mesh is
// assigned to exactly one incident triangle, its owner; every triangle owns its face. Testing, for
// an overlapping triangle pair (a, b), the features a owns against those b owns — owned vertices
// against the other face (VF) and owned edges against owned edges (EE) — visits each VF and EE
// feature pair once.
//
// The assignment is balanced greedily: edges, then vertices, each go to the incident triangle
// that owns the fewest features so far (ties to the lowest index), so most triangles own about
// two features (a regular grid has ≈ 1.5 edges and 0.5 vertices per triangle). Deterministic.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/geometry/topology.hpp"

namespace pliant::collision {

// The features one triangle owns, as compact lists (the per-pair loops run over exactly these).
struct OwnedFeatures {
    std::int32_t vertices[3];  // vertex ids, the first num_vertices valid
    std::int32_t edges[3];     // edge ids (MeshTopology::edges), the first num_edges valid
    std::uint8_t num_vertices = 0;
    std::uint8_t num_edges = 0;
};

struct RepresentativeTriangles {
    std::vector<std::int32_t> vertex_owner;  // #V: owning triangle, -1 for an isolated vertex
    std::vector<std::int32_t> edge_owner;    // #E: owning triangle
    std::vector<OwnedFeatures> owned;        // #T, ids ascending within each list
};

RepresentativeTriangles assign_representative_triangles(
    std::span<const geometry::Triangle> triangles, const geometry::MeshTopology& topology);

}  // namespace pliant::collision
