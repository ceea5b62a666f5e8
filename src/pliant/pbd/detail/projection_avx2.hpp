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

// A run of edges: edge q joins first + stride q and first + stride q + span (stride 1 or 2),
// `rest_lengths` parallel to them. Projects the first count − count mod 8 and returns that number.
std::int64_t project_edge_run_avx2(Float4* x, std::int64_t first, std::int32_t stride,
                                   std::int32_t span, const float* rest_lengths, std::int64_t count,
                                   float inv_k, float alpha);

// Tets of a regular lattice (TetGrid full box, vertex index = lattice index): tet q of the run has
// vertices base + 2 q + offsets[m] (every other cell along x), `rest_volumes` parallel to them.
// Projects the first count − count mod 8 and returns that number, and flags the tets at risk in
// at_risk, as above.
std::int64_t project_tet_run_avx2(Float4* x, std::int64_t base,
                                  const std::array<std::int32_t, 4>& offsets,
                                  const float* rest_volumes, std::uint8_t* at_risk,
                                  std::int64_t count, float inv_k, float alpha,
                                  std::int64_t& num_at_risk);

// Positions and this substep's inverse masses as four arrays (structure of arrays, world units),
// indexed by the lattice sweep's solver index (lattice_sweep.hpp).
struct SoaPositions {
    float* x = nullptr;
    float* y = nullptr;
    float* z = nullptr;
    float* w = nullptr;
};

// A run of edges on SoaPositions: edge q ∈ [0, count) joins a + q and b + q, `rest_lengths`
// parallel to them. Projects all count, 8 at a time, the last count mod 8 in masked lanes (the
// arithmetic of project_edge lane by lane).
void project_edge_run_soa_avx2(const SoaPositions& p, std::int32_t a, std::int32_t b,
                               const float* rest_lengths, std::int64_t count, float inv_k,
                               float alpha);

// A run of tets on SoaPositions: tet q ∈ [0, count) has vertices first[m] + q, `rest_volumes` and
// at_risk parallel to them. Projects all count as above, flags the tets at risk (at_risk[q] = 1,
// the others untouched) and adds their number to num_at_risk.
void project_tet_run_soa_avx2(const SoaPositions& p, const geometry::Tet& first,
                              const float* rest_volumes, std::uint8_t* at_risk, std::int64_t count,
                              float inv_k, float alpha, std::int64_t& num_at_risk);

}  // namespace pliant::pbd::detail
