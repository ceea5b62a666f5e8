// The edges of a tetrahedral mesh: the unique undirected vertex pairs {a, b}, a < b, of its tets'
// six edges each, sorted by (a, b). #E.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/geometry/tet_mesh.hpp"

namespace pliant::pbd {

// tets: #T (indices in [0, num_vertices), checked by the caller). O(#T log) work, deterministic.
std::vector<std::array<std::int32_t, 2>> tet_edges(std::span<const geometry::Tet> tets,
                                                   std::int64_t num_vertices);

}  // namespace pliant::pbd
