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
// kept neighbour (a parent). Two parents of one child are joined by a level-(l + 1) limit whose
// rest length is the shortest two-link path through a common child, p–c–q, summed from level l's
// rest lengths: a path's rest length, at least the straight rest distance, so a limit never
// asks for less than the cloth can give without stretching an edge, whatever the rest shape
// (flat or folded). Levels are built until one has fewer than MIN_VERTICES vertices or no
// limits, at most MAX_LEVELS.
//
// Limits. Unilateral: a limit p–q with rest length L projects only when |x_p − x_q| >
// (1 + max_strain) L, moving p and q along their line by the inverse-mass split of RELAXATION
// times the excess, capped at max_move (PBD, no compliance: a limit, not an elastic force), and
// never when compressed (cloth buckles). Pinned vertices (inverse mass 0) do not move. Where the
// limit cannot be met (strain imposed by moving pins, as in the twist scene) it keeps pulling
// every substep: the cap keeps those pulls within what the self-collision handles.
//
// One project() call, coarsest level first: project the level's limits (colour by colour, each
// colour in parallel; constraint_coloring.hpp), then move each of its children by the
// inverse-rest-length-weighted mean displacement of its parents (since the call began), down to
// level 0's children. The solver runs it before the mesh's own stretch and bending projections
// every substep (solver.hpp). Deterministic and bitwise identical for 1 and N threads.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/cloth/constraint_coloring.hpp"
#include "pliant/cloth/detail/constraint_kernels.hpp"
#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::cloth {

class StrainHierarchy {
public:
    static constexpr int MAX_LEVELS = 10;
    static constexpr std::int64_t MIN_VERTICES = 8;
    // The fraction of a limit's excess one projection removes. A stiff limit (1) turns a large
    // excess into a jump of centimetres within one substep, i.e. metres per second: after the
    // self-collision fail-safe has put vertices back (self_collision.hpp), such jumps cascaded
    // into more put-backs (the drape: 6,328 CCD hits in one frame, strain up to 570 %); a fifth
    // per substep removes 99.9 % of a small excess within 32 substeps, under a frame.
    static constexpr double RELAXATION = 0.2;

    // One coarse level: its limits between kept vertices and how its children (the finer level's
    // vertices it dropped) follow their parents.
    struct Level {
        std::vector<std::int32_t> vertices;  // kept vertices (mesh indices), ascending
        // Limits in colour order: p[k]–q[k], rest length rest[k] (metres); colours.offsets
        // delimit the colours.
        ConstraintColoring colors;
        std::vector<std::int32_t> p;
        std::vector<std::int32_t> q;
        std::vector<double> rest;
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
