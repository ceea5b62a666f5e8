// The soft body's constraints laid out for its colour sweep (soft_body.hpp, "Parallelism"): the
// edge-distance and tet-volume constraints in colour order with their rest lengths and volumes,
// and, on a TetGrid, the lattice structure the sweep exploits: runs of constraints whose vertices
// follow from one index (the AVX2 kernels derive them instead of loading them) and the layer
// blocking that sweeps the body slab by slab with the results of the colour-by-colour order.
// Built once by SoftBody's constructor, O(#E log #E + #T); internal to SoftBody.
#pragma once

#include <array>
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

// The tets of one colour of a full-box TetGrid, whose vertex index is the lattice index: cells of
// one parity class in lattice order, tet q of the colour in cell (i0 + 2 a, j0 + 2 b, k0 + 2 c)
// with q = a + ni (b + nj c), its vertices the cell's base index + offsets[m]. The AVX2 kernel
// derives the vertices from the base instead of loading them.
struct TetRun {
    std::array<std::int32_t, 4> offsets{};
    std::int64_t i0 = 0, j0 = 0, k0 = 0;
    std::int64_t ni = 0, nj = 0, nk = 0;
};

// A run of edges of one colour: edge q ∈ [begin, next run's begin) joins first + stride (q − begin)
// and that + span (stride 1 or 2). On a TetGrid nearly every edge lies in a run of a lattice row.
struct EdgeRun {
    std::int64_t begin = 0;
    std::int32_t first = 0;
    std::int32_t stride = 1;
    std::int32_t span = 0;
};

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

// The edge-distance constraints C = |x_a − x_b| − L in colour order: colour c holds the entries
// [coloring.offsets[c], coloring.offsets[c + 1]) of every per-constraint array. On a grid the
// edges of a colour are ordered by layer and direction (for the runs), which changes no result:
// they share no vertex.
struct EdgeConstraints {
    ConstraintColoring coloring;                        // of SoftBody::edges()
    std::vector<std::array<std::int32_t, 2>> vertices;  // #E, a < b
    std::vector<float> rest_lengths0;                   // #E, world units, at construction
    std::vector<float> rest_lengths;                    // #E, current (rest-state drivers)
    // On a TetGrid: the runs of `vertices`, those of colour c at runs[run_offsets[c] ..
    // run_offsets[c + 1]), run_begins[r] = runs[r].begin; all empty for other meshes.
    std::vector<EdgeRun> runs;
    std::vector<std::int64_t> run_begins;
    std::vector<std::int64_t> run_offsets;
    LayerBlocking blocking;  // on a TetGrid; none otherwise
};

// The tet-volume constraints C = V − V0 in colour order, as EdgeConstraints; a tet's vertices are
// in input order (the orientation of V).
struct TetConstraints {
    ConstraintColoring coloring;          // of SoftBody::tets()
    std::vector<geometry::Tet> vertices;  // #T
    std::vector<float> rest_volumes0;     // #T, world units³, at construction
    std::vector<float> rest_volumes;      // #T, current (rest-state drivers)
    // Per colour of a full-box TetGrid (TetRun); empty for other meshes.
    std::vector<TetRun> runs;
    std::int64_t lattice_x = 0;   // lattice vertices along x (TetGrid)
    std::int64_t lattice_xy = 0;  // … in one z layer
    LayerBlocking blocking;       // on a TetGrid; none otherwise
};

// The edges (#E, a < b, indices into rest: #V, world units) in the order of `coloring`, their
// rest lengths |rest_a − rest_b| (computed in double, stored as float); on a grid (nullptr for
// other meshes; its lattice matches rest) also their runs and layer blocking.
EdgeConstraints layout_edge_constraints(ConstraintColoring coloring,
                                        std::span<const std::array<std::int32_t, 2>> edges,
                                        std::span<const Vec3f> rest, const TetGrid* grid);

// The tets (#T, indices in [0, num_vertices)) in the order of `coloring`, with rest_volumes (#T,
// input order, world units³); on a grid (nullptr for other meshes) also their runs (full box
// only) and layer blocking.
TetConstraints layout_tet_constraints(ConstraintColoring coloring,
                                      std::span<const geometry::Tet> tets,
                                      std::span<const double> rest_volumes,
                                      std::int64_t num_vertices, const TetGrid* grid);

}  // namespace pliant::pbd::detail
