// How much memory a cloth simulation needs, against what the machine has: a cloth too large to
// simulate is refused before it is generated or simulated, instead of being killed by the
// operating system hours of swapping later.
#pragma once

#include <cstdint>
#include <string>

namespace pliant::pipeline {

// The least memory a cloth simulation takes per triangle (bytes), from the peak resident size of
// one frame of falling grid sheets without contact: with self-collision 1.31 KB at 1000 x 1000
// quads (2 million triangles; 1.39 KB at 536 x 536, more on smaller sheets and in contact),
// without 0.53 KB at 2000 x 2000 quads.
inline constexpr std::uint64_t CLOTH_BYTES_PER_TRIANGLE = 500;
inline constexpr std::uint64_t SELF_COLLIDING_CLOTH_BYTES_PER_TRIANGLE = 1300;

// The memory this process may use, in bytes: the machine's physical memory, or the control
// group's limit when lower (cgroup v2 memory.max, v1 memory.limit_in_bytes); 0 when neither
// can be determined.
std::uint64_t available_memory_bytes();

// Throws InvalidInput "<what>: <triangles> triangles need at least <X GB or MB> to simulate,
// more than the <Y GB or MB> of memory available" when triangles times the bytes per triangle above
// (with or without self-collision) exceeds memory_bytes (0: unknown, no check).
void require_cloth_fits_in_memory(const std::string& what, std::uint64_t triangles,
                                  bool self_collision, std::uint64_t memory_bytes);

}  // namespace pliant::pipeline
