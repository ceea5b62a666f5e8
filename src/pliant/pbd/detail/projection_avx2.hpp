// AVX2 versions of the SSE kernels of projection.hpp: 8 constraints of one colour at a time (their
// vertices distinct), compiled for AVX2 with a function attribute and chosen at run time
// (pliant::has_avx2(), core/simd_dispatch.hpp). The arithmetic is that of project_edge /
// project_tet lane by lane, in the same order and without FMA contraction: results are bitwise
// those of the SSE and scalar kernels, so the choice of kernel never changes a result (on any
// machine, for any number of threads).
#pragma once

#include <array>
#include <cstdint>

#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/pbd/detail/projection.hpp"

namespace pliant::pbd::detail {

// Edges e[0 .. count) of one colour, `rest_lengths` parallel to them; projects the first
// count − count mod 8 and returns that number (the caller projects the rest).
std::int64_t project_edges_avx2(Float4* x, const std::array<std::int32_t, 2>* e,
                                const float* rest_lengths, std::int64_t count, float inv_k,
                                float alpha);

// Tets t[0 .. count) of one colour, the same way; at_risk parallel to them: at_risk[q] = 1 for the
// tets at risk (projection.hpp), the others' entries untouched, their number added to num_at_risk.
std::int64_t project_tets_avx2(Float4* x, const geometry::Tet* t, const float* rest_volumes,
                               std::uint8_t* at_risk, std::int64_t count, float inv_k, float alpha,
                               std::int64_t& num_at_risk);

// Positions and this substep's inverse masses as four arrays (structure of arrays, world units),
// indexed by the lattice sweep's solver index (lattice_sweep.hpp).
struct SoaPositions {
    float* x = nullptr;
    float* y = nullptr;
    float* z = nullptr;
    float* w = nullptr;
};

// A run of constraints of one colour in the solver order (lattice_sweep.hpp): constraint
// q ∈ [begin, next run's begin) has vertices first[m] + (q − begin) (edges: m = 0, 1).
struct LatticeRun {
    std::int64_t begin = 0;
    geometry::Tet first{};
};

// The runs of one colour: runs[0 .. num_runs), run_begins[r] = runs[r].begin, the colour's
// constraints [begin, begin + count) in the colour order.
struct LatticeRuns {
    const LatticeRun* runs = nullptr;
    const std::int64_t* run_begins = nullptr;
    std::int64_t num_runs = 0;
    std::int64_t begin = 0;
    std::int64_t count = 0;
};

// Edges [b, e) of a colour (indices within it) on SoaPositions, `rest_lengths` the colour's:
// every run's piece in [b, e) 8 at a time, its last count mod 8 in masked lanes (the arithmetic
// of project_edge lane by lane).
void project_edge_runs_soa_avx2(const SoaPositions& p, const LatticeRuns& runs, std::int64_t b,
                                std::int64_t e, const float* rest_lengths, float inv_k,
                                float alpha);

// Tets [b, e) of a colour the same way, `rest_volumes` and at_risk the colour's: flags the tets at
// risk (at_risk[q] = 1, the others untouched) and adds their number to num_at_risk.
void project_tet_runs_soa_avx2(const SoaPositions& p, const LatticeRuns& runs, std::int64_t b,
                               std::int64_t e, const float* rest_volumes, std::uint8_t* at_risk,
                               float inv_k, float alpha, std::int64_t& num_at_risk);

}  // namespace pliant::pbd::detail
