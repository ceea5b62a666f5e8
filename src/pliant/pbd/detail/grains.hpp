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

}  // namespace pliant::pbd::detail
