#include "pliant/pbd/tet_edges.hpp"

#include <algorithm>

#include "pliant/core/parallel.hpp"

namespace pliant::pbd {

std::vector<std::array<std::int32_t, 2>> tet_edges(std::span<const geometry::Tet> tets,
                                                   std::int64_t num_vertices) {
    // Bucket every tet edge under its smaller vertex (CSR: count, prefix, fill), then sort and
    // deduplicate each vertex's short list: O(#T) plus small sorts, and the order (a, b) falls out.
    const auto nv = static_cast<std::size_t>(num_vertices);
    std::vector<std::int64_t> start(nv + 1, 0);
    static constexpr std::array<std::array<int, 2>, 6> TET_EDGES{
        {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};
    for (const geometry::Tet& t : tets) {
        for (const auto& e : TET_EDGES) {
            const std::int32_t a = std::min(t[e[0]], t[e[1]]);
            ++start[static_cast<std::size_t>(a) + 1];
        }
    }
    for (std::size_t v = 0; v < nv; ++v) {
        start[v + 1] += start[v];
    }
    std::vector<std::int32_t> other(static_cast<std::size_t>(start[nv]));
    std::vector<std::int64_t> fill(start.begin(), start.end() - 1);
    for (const geometry::Tet& t : tets) {
        for (const auto& e : TET_EDGES) {
            const std::int32_t a = std::min(t[e[0]], t[e[1]]);
            const std::int32_t b = std::max(t[e[0]], t[e[1]]);
            other[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b;
        }
    }
    // Per vertex: sort, unique; count the survivors.
    std::vector<std::int64_t> unique_count(nv + 1, 0);
    parallel_for(
        num_vertices,
        [&](std::int64_t v) {
            auto* begin = other.data() + start[static_cast<std::size_t>(v)];
            auto* end = other.data() + start[static_cast<std::size_t>(v) + 1];
            std::sort(begin, end);
            unique_count[static_cast<std::size_t>(v) + 1] = std::unique(begin, end) - begin;
        },
        1024);
    for (std::size_t v = 0; v < nv; ++v) {
        unique_count[v + 1] += unique_count[v];
    }
    std::vector<std::array<std::int32_t, 2>> edges(static_cast<std::size_t>(unique_count[nv]));
    parallel_for(
        num_vertices,
        [&](std::int64_t v) {
            const auto vi = static_cast<std::size_t>(v);
            const std::int64_t n = unique_count[vi + 1] - unique_count[vi];
            for (std::int64_t i = 0; i < n; ++i) {
                edges[static_cast<std::size_t>(unique_count[vi] + i)] = {
                    static_cast<std::int32_t>(v), other[static_cast<std::size_t>(start[vi] + i)]};
            }
        },
        1024);
    return edges;
}

}  // namespace pliant::pbd
