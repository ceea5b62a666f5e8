// AVX2 version of the velocity update and prediction between two substeps (integration.hpp's
// substep_velocity and predict_vertex) on the lattice sweep's solver-order arrays
// (lattice_sweep.hpp), 8 vertices at a time, compiled for AVX2 with a function attribute and
// chosen at run time (pliant::has_avx2()). The arithmetic is the scalar kernels' lane by lane, in
// the same order and without FMA contraction: the same bits.
#pragma once

#include <cstdint>

#include "pliant/pbd/detail/integration.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"

namespace pliant::pbd::detail {

// The solver-order arrays one substep's end reads and writes: positions and inverse masses p
// (world units, 1/kg; the substep's w), the positions at the substep's start (previous_*), the
// vertices' inverse masses and pinned flags (1 = pinned).
struct SoaMotion {
    SoaPositions p;
    float* previous_x = nullptr;
    float* previous_y = nullptr;
    float* previous_z = nullptr;
    const float* inv_masses = nullptr;
    const std::uint8_t* pinned = nullptr;
};

// Vertices [begin, end): v = 0 if pinned, else substep_velocity; then predict_vertex with v
// (previous = the position, a free vertex moved by h (v + g h), p.w = its inverse mass or 0).
void finish_substep_soa_avx2(const SoaMotion& a, std::int64_t begin, std::int64_t end,
                             const SubstepMotion& m);

}  // namespace pliant::pbd::detail
