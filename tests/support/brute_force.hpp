// Brute-force references: O(n²) enumerations that the fast paths are checked against.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "pliant/core/aabb.hpp"

namespace pliant::test {

using Pair = std::pair<std::uint32_t, std::uint32_t>;

// Every unordered pair (a < b) of overlapping boxes, sorted.
std::vector<Pair> brute_force_self_overlaps(std::span<const AABB> boxes);
// Every (a, b) with boxes_a[a] overlapping boxes_b[b], sorted.
std::vector<Pair> brute_force_overlaps(std::span<const AABB> boxes_a,
                                       std::span<const AABB> boxes_b);
// Pairs normalised to (min, max) and sorted, for comparison with brute force.
std::vector<Pair> normalized(std::vector<Pair> pairs);

}  // namespace pliant::test
