// The soft body's constraints laid out for its colour sweep (soft_body.hpp, "Parallelism"): the
// edge-distance and tet-volume constraints in colour order with their rest lengths and volumes,
// and, on a TetGrid, the layer blocking that sweeps the body slab by slab with the results of the
// colour-by-colour order (lattice_sweep.hpp then orders each colour's layers into runs).
// Built once by SoftBody's constructor, O(#E log #E + #T); internal to SoftBody.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/pbd/constraint_coloring.hpp"
#include "pliant/pbd/tet_grid.hpp"

namespace pliant::pbd::detail {

// Lattice layers per slab of the blocked sweep (LayerBlocking): enough constraints per colour for
// a few chunks, few enough that a slab's vertices stay in the L2 cache.
inline constexpr std::int64_t LAYERS_PER_SLAB = 4;

// Layer blocking of a grid's colour sweep, for cache reuse. Every constraint has a layer key z
// (its lowest lattice z; a tet, its cell's), every vertex it holds lies in layer z or z + 1, and a
// colour's constraints are sorted by key. The sweep runs slab after slab; in slab t colour c
// projects its constraints of layers [t − skew[c], t − skew[c] + LAYERS_PER_SLAB). The skews are
// the smallest with skew[c'] − skew[c] ≥ z − z' for every two constraints of colours c < c' (z,
// z' their keys) that share a vertex: such a pair then lands in slabs t ≤ t', and colours run in
// order within a slab, so every two constraints sharing a vertex are projected in the order of
// their colours, as in the plain colour-by-colour sweep (constraints sharing no vertex commute):
// the results are bitwise those of the plain sweep. A slab touches LAYERS_PER_SLAB + max_skew + 1
// vertex layers rather than the whole body per colour.
struct LayerBlocking {
    std::int64_t num_layers = 0;  // 0: no blocking (plain sweep)
    std::int64_t max_skew = 0;
    std::vector<std::int64_t> skew;  // per colour
    // Per colour c, at c · (num_layers + 1) + z: the first constraint of the colour (index within
    // the colour) with key ≥ z.
    std::vector<std::int64_t> layer_begin;
};

// Lattice coordinate `axis` (0 x, 1 y, 2 z) of every vertex of a grid (#V).
std::vector<std::int32_t> vertex_lattice_axis(const TetGrid& grid, int axis);

// The smallest skews per colour with skew[c'] − skew[c] ≥ k − k' for every two constraints of
// colours c < c' (in coloring's order; k, k' their keys) that share a vertex, every vertex a
// constraint holds lying at level key or key + 1 (vertex_level: per vertex): LayerBlocking's
// skews in z, and LatticeSweep's lanes' in y. Empty when a vertex lies elsewhere, or for more
// than 64 colours. K = 2 (edges) or 4 (tets).
template <std::size_t K>
std::vector<std::int64_t> colour_skews(const ConstraintColoring& coloring,
                                       const std::vector<std::array<std::int32_t, K>>& constraints,
                                       const std::vector<std::int32_t>& keys,
                                       const std::vector<std::int32_t>& vertex_level);

// The edge-distance constraints C = |x_a − x_b| − L in colour order: colour c holds the entries
// [coloring.offsets[c], coloring.offsets[c + 1]) of every per-constraint array. On a grid the
// edges of a colour are ordered by layer, which changes no result: they share no vertex.
struct EdgeConstraints {
    ConstraintColoring coloring;                        // of SoftBody::edges()
    std::vector<std::array<std::int32_t, 2>> vertices;  // #E, a < b
    std::vector<float> rest_lengths0;                   // #E, world units, at construction
    std::vector<float> rest_lengths;                    // #E, current (rest-state drivers)
    LayerBlocking blocking;                             // on a TetGrid; none otherwise
};

// The tet-volume constraints C = V − V0 in colour order, as EdgeConstraints; a tet's vertices are
// in input order (the orientation of V).
struct TetConstraints {
    ConstraintColoring coloring;          // of SoftBody::tets()
    std::vector<geometry::Tet> vertices;  // #T
    std::vector<float> rest_volumes0;     // #T, world units³, at construction
    std::vector<float> rest_volumes;      // #T, current (rest-state drivers)
    LayerBlocking blocking;               // on a TetGrid; none otherwise
};

// The edges (#E, a < b, indices into rest: #V, world units) in the order of `coloring`, their
// rest lengths |rest_a − rest_b| (computed in double, stored as float); on a grid (nullptr for
// other meshes; its lattice matches rest) ordered by layer within each colour, with their layer
// blocking.
EdgeConstraints layout_edge_constraints(ConstraintColoring coloring,
                                        std::span<const std::array<std::int32_t, 2>> edges,
                                        std::span<const Vec3f> rest, const TetGrid* grid);

// The tets (#T) in the order of `coloring`, with rest_volumes (#T, input order, world units³); on
// a grid (nullptr for other meshes) also their layer blocking.
TetConstraints layout_tet_constraints(ConstraintColoring coloring,
                                      std::span<const geometry::Tet> tets,
                                      std::span<const double> rest_volumes, const TetGrid* grid);

}  // namespace pliant::pbd::detail
