// The soft body's fixed chunk sizes for parallel_for (core/parallel.hpp): chunk boundaries depend
// only on the count and these grains, never on the number of threads. Multiples of 8: a chunk
// holds whole groups of the SIMD kernels (4 or 8 constraints), so scalar remainders are left only
// at the end of a range.
#pragma once

#include <cstdint>

namespace pliant::pbd::detail {

inline constexpr std::int64_t VERTEX_GRAIN = 4096;  // vertices per chunk
inline constexpr std::int64_t EDGE_GRAIN = 2048;    // edge constraints per chunk
inline constexpr std::int64_t TET_GRAIN = 1024;     // tet constraints per chunk
// The lattice sweep's (lattice_sweep.hpp): a layer-blocked slab of one colour holds about 2,000
// edges and 800 tets at 64³ cells, so that smaller chunks give each of 2 threads work in every
// slab (with the grains above most slabs were one chunk, one thread).
inline constexpr std::int64_t LATTICE_EDGE_GRAIN = 512;
inline constexpr std::int64_t LATTICE_TET_GRAIN = 256;
// Runs of the lattice sweep per chunk where whole runs are the unit (the waves' rest state:
// about 16 constraints per run at the source's scale).
inline constexpr std::int64_t RUN_GRAIN = 256;

// Lanes of the lattice sweep (lattice_sweep.hpp): bands of lattice rows pipelined on as many
// threads.
inline constexpr std::int64_t SWEEP_LANES = 2;

}  // namespace pliant::pbd::detail
