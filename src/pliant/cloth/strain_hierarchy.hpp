// StrainHierarchy: multi-resolution strain limiting for cloth, after Müller, "Hierarchical
// Position Based Dynamics" (VRIPHYS 2008), used as a strain limit (as in Wang, O'Brien,
// Ramamoorthi, "Multi-resolution isotropic strain limiting", SIGGRAPH Asia 2010).
//
// Why: one Gauss-Seidel sweep per substep moves a correction one or two edges along the cloth,
// so a long hanging piece stretches far beyond its compliance before the sweeps catch up (the
// drape's skirt: 13 % strain at rest, 34 % at the impact). Coarse levels carry the correction
// across the cloth in one pass.
//
// Levels. Level 0 is the mesh (its edges are the solver's stretch constraints). Level l + 1 keeps
// a maximal independent set of level l's vertices (greedy in ascending vertex order: a vertex is
// kept unless a neighbour was kept before it), so every dropped vertex (a child) has at least one
// kept neighbour (a parent). Every two parents of one child are joined by a level-(l + 1) limit
// whose rest length is the shortest path between them along the rest mesh's edges (Dijkstra): if
// no edge is longer than at rest, no two vertices are farther apart than that, whatever the rest
// shape (flat or folded), so a limit never asks for less than the cloth can give. (An edge path
// is longer than the straight distance where no edge runs that way: up to √2 × across the
// diagonals of a grid's quads.) Vertices left without a limit take no further part. Levels are
// built until one would have fewer than MIN_VERTICES vertices, keep more than MAX_KEPT_FRACTION of
// the finer level's, have no limit, or give a vertex more than MAX_LIMITS_PER_VERTEX limits (the
// colouring's bound), at most MAX_LEVELS; a mesh of fewer than MIN_VERTICES linked vertices has no
// level and no limit. (MAX_KEPT_FRACTION and MAX_LIMITS_PER_VERTEX: strain_hierarchy.cpp.)
//
// Limits. Unilateral: a limit p–q with rest length L acts only when |x_p − x_q| > (1 +
// max_strain) L, moving p and q along their line by the inverse-mass split of RELAXATION times
// the excess, at most max_move per limit and call (a vertex in several limits, on several
// levels, can move several times that) (PBD, no compliance: a limit, not an elastic force), and
// never when they are closer (cloth buckles). Pinned vertices (inverse mass 0) do not move. Only
// the limits' ends are measured: strain between them is left to the finer levels and, at level
// 0, to the edges' own constraints. Where a limit cannot be met (strain imposed by moving pins,
// as in the twist scene) it keeps pulling every substep.
//
// One project() call, coarsest level first: project the level's limits (colour by colour, each
// colour in parallel; constraint_coloring.hpp), then move each of its children by the
// inverse-rest-length-weighted mean displacement of its parents (since the call began), down to
// level 0's children. The solver runs it before the mesh's own stretch and bending projections
// every substep (solver.hpp). Deterministic and bitwise identical for 1 and N threads.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/constraint_coloring.hpp"
#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/core/host_device.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

namespace detail {

// One limit: p and q are pulled together along their line, split by inverse mass, by
// `relaxation` times their excess over max_length but at most max_move (metres); nothing when
// they are at most max_length apart or both fixed (inverse mass 0).
PLIANT_HOST_DEVICE inline void limit_stretch(PackedVertex* x, std::int32_t p, std::int32_t q,
                                             double max_length, double relaxation,
                                             double max_move) {
    PackedVertex& a = x[p];
    PackedVertex& b = x[q];
    const double w = a.inverse_mass + b.inverse_mass;
    if (!(w > 0.0)) {
        return;
    }
    const double dx = a.x - b.x;
    const double dy = a.y - b.y;
    const double dz = a.z - b.z;
    const double length_squared = dx * dx + dy * dy + dz * dz;
    if (!(length_squared > max_length * max_length)) {
        return;
    }
    const double length = std::sqrt(length_squared);
    const double excess = relaxation * (length - max_length);
    const double s = (excess < max_move ? excess : max_move) / (length * w);
    const double sa = a.inverse_mass * s;
    const double sb = b.inverse_mass * s;
    a.x -= dx * sa;
    a.y -= dy * sa;
    a.z -= dz * sa;
    b.x += dx * sb;
    b.y += dy * sb;
    b.z += dz * sb;
}

}  // namespace detail

class StrainHierarchy {
public:
    static constexpr int MAX_LEVELS = 10;
    static constexpr std::int64_t MIN_VERTICES = 8;
    // The fraction of a limit's excess one projection removes. A stiff limit (1) turns a large
    // excess into a jump of centimetres within one substep, i.e. metres per second: after the
    // self-collision fail-safe has put vertices back (self_collision.hpp), such jumps cascade
    // into more put-backs (docs/journal/2026-11-25-strain-limiting.md). A fifth per substep
    // leaves 0.8^32 < 0.1 % of an excess after 32 substeps while max_move does not bind.
    static constexpr double RELAXATION = 0.2;

    // One coarse level: its limits between kept vertices and how its children (the finer level's
    // vertices it dropped) follow their parents.
    struct Level {
        std::vector<std::int32_t> vertices;  // kept vertices (mesh indices), ascending
        // The limits p–q with their rest lengths (metres), coloured, in colour order.
        ColoredEdges limits;
        // Children (mesh indices, ascending) and their parents: child k's parents are
        // parents[parent_offsets[k] .. parent_offsets[k + 1]), with weights summing to 1.
        std::vector<std::int32_t> children;
        std::vector<std::int32_t> parent_offsets;
        std::vector<std::int32_t> parents;
        std::vector<double> weights;
    };

    StrainHierarchy() = default;
    // The mesh's vertex count, its edges and their rest lengths (metres, ≥ 0). Precondition:
    // edges index [0, num_vertices) and are unique (geometry::build_topology's edges).
    StrainHierarchy(std::int64_t num_vertices, std::span<const geometry::Edge> edges,
                    std::span<const double> rest_lengths);

    // Projects every level's limits at strain max_strain (≥ 0), coarsest first, and prolongs the
    // corrections down to the mesh's vertices. A limit closes RELAXATION times its excess, but at
    // most max_move (metres; infinity: no cap) of it per call. x: the mesh's vertices, packed
    // (inverse mass 0 = fixed). No-op without levels.
    void project(detail::PackedVertex* x, double max_strain, double max_move);

    std::size_t num_levels() const { return m_levels.size(); }
    // Level 1 … num_levels(): m_levels[l − 1].
    const Level& level(std::size_t l) const { return m_levels[l - 1]; }
    std::size_t num_limits() const;

private:
    std::vector<Level> m_levels;
    std::vector<Vec3d> m_start;  // positions of level 1's vertices when project() began
};

}  // namespace pliant::cloth
