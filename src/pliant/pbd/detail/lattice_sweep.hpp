// The soft body's constraint sweep on a TetGrid with AVX2 (soft_body.hpp, steps 2 and 3): the
// vertices in a solver order where the constraints of a colour form runs of consecutive vertices,
// positions as four float arrays (structure of arrays), so that 8 constraints load and store
// their vertices with plain vector loads instead of transposing 16-byte vertices.
//
// Solver order: lattice rows (z, then y), within a row the kept vertices of even lattice x, then
// those of odd x. The cells of one parity class along a row step by 2 in x, so a corner of their
// tets, and the ends of their edges, step by one in the solver order. Within each colour and each
// layer key (constraint_layout.hpp, LayerBlocking) the constraints are reordered (with their rest
// data) so that runs of constraints whose every vertex steps by one are consecutive; a run of any
// length is projected 8 at a time, its last count mod 8 in masked lanes. The order within a colour
// changes no result (its constraints share no vertex), the layer keys and so the blocking stay,
// and the kernels are project_edges8 / project_tets8's arithmetic: results are bitwise those of
// the plain colour-by-colour sweep (constraint_sweep.hpp), for any number of threads.
//
// project_lattice copies x into the arrays, runs the blocked edge and tet sweeps on them, and
// copies the positions back (#V each way, parallel); a step of one plain iteration instead copies
// x in once and runs every stage of every substep on the arrays (load_lattice ..
// finish_lattice_step).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/pbd/detail/constraint_layout.hpp"
#include "pliant/pbd/detail/constraint_sweep.hpp"
#include "pliant/pbd/detail/integration.hpp"
#include "pliant/pbd/detail/inversion_guard.hpp"
#include "pliant/pbd/detail/projection.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"
#include "pliant/pbd/tet_grid.hpp"

namespace pliant::pbd::detail {

struct LatticeSweep {
    std::vector<std::int32_t> vertex_of;     // #V: the vertex at each solver index
    std::vector<std::int32_t> solver_index;  // #V: the solver index of each vertex
    // Runs (projection_avx2.hpp) of colour c at runs[run_offsets[c] .. run_offsets[c + 1]),
    // run_begins[r] = runs[r].begin.
    std::vector<LatticeRun> edge_runs;
    std::vector<std::int64_t> edge_run_begins;
    std::vector<std::int64_t> edge_run_offsets;
    std::vector<LatticeRun> tet_runs;
    std::vector<std::int64_t> tet_run_begins;
    std::vector<std::int64_t> tet_run_offsets;
    // Lanes: every constraint of colour c with row key y (lowest lattice y) is in lane
    // #{boundaries ≤ y + row_skew[c]} of SWEEP_LANES, with the smallest row skews such that two
    // constraints sharing a vertex are in lanes l ≤ l' when their colours are c < c' (as
    // LayerBlocking's skews in z), boundaries splitting the constraints in about equal parts.
    // Within each colour and layer key the constraints are ordered by lane, and a slab of one lane
    // depends only on slabs ≤ it of lanes ≤ it: the lanes run as a pipeline, each a slab behind
    // the previous, with no barrier between colours. lane_begin: per colour c, at
    // c · (num_layers · SWEEP_LANES + 1) + z · SWEEP_LANES + l, the first constraint (index within
    // the colour) of layer key ≥ z in lane ≥ l; empty: no lanes. On one thread, or without
    // lanes, the blocked sweep runs each colour of a slab in fixed chunks (the same bits).
    std::vector<std::int64_t> edge_lane_begin;
    std::vector<std::int64_t> tet_lane_begin;
    // #V each, solver order: the substep's positions (world units) and inverse masses.
    std::vector<float> x, y, z, w;
    // #V each, solver order, within a step in solver order (load_lattice .. finish_lattice_step):
    // the positions at the substep's start, the inverse masses (1/kg, 0 = pinned or in no tet) and
    // the pinned flags.
    std::vector<float> previous_x, previous_y, previous_z, inv_masses;
    std::vector<std::uint8_t> pinned;
};

// The sweep of a grid's constraints (laid out by constraint_layout.hpp for that grid): reorders
// edges' and tets' constraints (vertices and rest data, current and at construction) within each
// colour and layer key, and builds the runs. The other sweeps (constraint_sweep.hpp: SSE, scalar)
// read the vertices and stay valid.
LatticeSweep build_lattice_sweep(const TetGrid& grid, EdgeConstraints& edges, TetConstraints& tets);

// Steps 2 and 3 on x (#V, world units, packed with the substep's inverse mass; read and written):
// every edge, then every tet, in the order of sweep_colours, flagging the tets at risk as
// project_tets does. Requires AVX2 (pliant::has_avx2()).
void project_lattice(Float4* x, LatticeSweep& sweep, const EdgeConstraints& edges,
                     const TetConstraints& tets, ConstraintStiffness edge_stiffness,
                     ConstraintStiffness tet_stiffness, std::span<std::uint8_t> tet_at_risk,
                     std::span<std::uint8_t> colour_at_risk);

// A whole step on the arrays (soft_body.hpp's step with one plain iteration): x copied into them
// once, the same arithmetic on the same values as project_lattice, guard_flagged_tets and the
// passes of integration.hpp on x, so the same bits.
//
// After the first substep's prediction: x's positions and inverse masses, previous, inv_masses
// and pinned (#V each) into the arrays.
void load_lattice(const Float4* x, std::span<const Vec3f> previous,
                  std::span<const float> inv_masses, std::span<const std::uint8_t> pinned,
                  LatticeSweep& sweep);
// x's entries of `vertices` (vertex indices) into the arrays (the driven vertices' targets).
void load_lattice_vertices(const Float4* x, std::span<const std::int32_t> vertices,
                           LatticeSweep& sweep);
// Steps 2 and 3 on the arrays (project_lattice without the copies).
void sweep_lattice(LatticeSweep& sweep, const EdgeConstraints& edges, const TetConstraints& tets,
                   ConstraintStiffness edge_stiffness, ConstraintStiffness tet_stiffness,
                   std::span<std::uint8_t> tet_at_risk, std::span<std::uint8_t> colour_at_risk);
// Step 3b on the arrays (guard_flagged_tets).
void guard_lattice(LatticeSweep& sweep, const TetConstraints& tets, InversionFlags& flags);
// Between substeps, on the arrays: update_velocities_and_predict's velocity and prediction
// (integration_avx2.hpp: AVX2, the same bits).
void finish_lattice_substep(LatticeSweep& sweep, const SubstepMotion& m);
// After the last substep: update_velocities's velocities and positions, and x and previous (#V)
// as the general loop leaves them.
void finish_lattice_step(const LatticeSweep& sweep, const SubstepMotion& m, Float4* x,
                         std::span<Vec3f> previous, std::span<Vec3f> velocities,
                         std::span<Vec3f> positions);

}  // namespace pliant::pbd::detail
