// EdgeStrain: how far a cloth's edges are stretched relative to a rest shape, an independent
// quality measure of an output frame (like the intersecting-pair count): it reads only the mesh,
// not the solver's constraints.
//
// Strain of an edge (dimensionless): ε = |x_a - x_b| / L - 1, L the edge's rest length; 0.1 is
// 10 % longer than at rest, negative values are compression (which cloth takes by buckling and
// is not reported here). Edges of zero rest length are skipped.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

struct StrainStats {
    double p90 = 0.0;  // 90th percentile of ε over the edges (nearest rank)
    double p99 = 0.0;  // 99th percentile
    double max = 0.0;  // largest ε
    // Edges stretched beyond 10 % and beyond 100 % of their rest length.
    std::int64_t over_10_percent = 0;
    std::int64_t over_100_percent = 0;
};

class EdgeStrain {
public:
    // The unique edges of `triangles` and their lengths in `rest_positions` (metres).
    // Precondition: triangles validated against rest_positions.size().
    EdgeStrain(std::span<const Vec3d> rest_positions,
               std::span<const geometry::Triangle> triangles);

    // Strain of every edge at `positions` (same vertex count as the rest shape; else
    // InvalidInput). Deterministic; O(E) plus two selections.
    StrainStats measure(std::span<const Vec3d> positions) const;

    std::size_t num_edges() const { return m_edges.size(); }

private:
    std::vector<geometry::Edge> m_edges;
    std::vector<double> m_rest_lengths;
    std::size_t m_num_vertices = 0;
};

}  // namespace pliant::cloth
