#include "pliant/cloth/vertex_coloring.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "pliant/core/error.hpp"

namespace pliant::cloth {

VertexColoring color_vertices(std::int64_t num_vertices, std::span<const std::int32_t> vertices,
                              std::span<const std::int32_t> element_offsets) {
    if (element_offsets.empty() || element_offsets.front() != 0 ||
        static_cast<std::size_t>(element_offsets.back()) != vertices.size()) {
        throw InvalidInput(fmt::format(
            "color_vertices: element_offsets must start at 0 and end at vertices.size() ({})",
            vertices.size()));
    }
    for (const std::int32_t v : vertices) {
        if (v < 0 || v >= num_vertices) {
            throw InvalidInput(fmt::format(
                "color_vertices: vertex {} out of range, expected [0, {})", v, num_vertices));
        }
    }
    const auto n = static_cast<std::size_t>(num_vertices);
    const std::size_t num_elements = element_offsets.size() - 1;
    // Elements per vertex (CSR), in element order.
    std::vector<std::int32_t> first(n + 1, 0);
    for (const std::int32_t v : vertices) {
        ++first[static_cast<std::size_t>(v) + 1];
    }
    for (std::size_t v = 0; v < n; ++v) {
        first[v + 1] += first[v];
    }
    std::vector<std::int32_t> elements_of(vertices.size());
    std::vector<std::int32_t> fill(first.begin(), first.end() - 1);
    for (std::size_t k = 0; k < num_elements; ++k) {
        for (auto i = element_offsets[k]; i < element_offsets[k + 1]; ++i) {
            const auto v = static_cast<std::size_t>(vertices[static_cast<std::size_t>(i)]);
            elements_of[static_cast<std::size_t>(fill[v]++)] = static_cast<std::int32_t>(k);
        }
    }
    // Greedy: the smallest colour no neighbour has; `mark[c] == v` marks colour c as taken for v.
    VertexColoring coloring;
    coloring.color_of.assign(n, -1);
    std::vector<std::int64_t> mark;
    std::int32_t num_colors = 0;
    for (std::size_t v = 0; v < n; ++v) {
        for (auto e = first[v]; e < first[v + 1]; ++e) {
            const auto k = static_cast<std::size_t>(elements_of[static_cast<std::size_t>(e)]);
            for (auto i = element_offsets[k]; i < element_offsets[k + 1]; ++i) {
                const std::int32_t c =
                    coloring
                        .color_of[static_cast<std::size_t>(vertices[static_cast<std::size_t>(i)])];
                if (c >= 0) {
                    mark[static_cast<std::size_t>(c)] = static_cast<std::int64_t>(v);
                }
            }
        }
        std::int32_t c = 0;
        while (c < num_colors &&
               mark[static_cast<std::size_t>(c)] == static_cast<std::int64_t>(v)) {
            ++c;
        }
        if (c == num_colors) {
            ++num_colors;
            mark.push_back(-1);
        }
        coloring.color_of[v] = c;
    }
    // Vertices by colour, ascending within a colour.
    coloring.offsets.assign(static_cast<std::size_t>(num_colors) + 1, 0);
    for (const std::int32_t c : coloring.color_of) {
        ++coloring.offsets[static_cast<std::size_t>(c) + 1];
    }
    for (std::size_t c = 0; c < static_cast<std::size_t>(num_colors); ++c) {
        coloring.offsets[c + 1] += coloring.offsets[c];
    }
    coloring.order.resize(n);
    std::vector<std::int32_t> next(coloring.offsets.begin(), coloring.offsets.end() - 1);
    for (std::size_t v = 0; v < n; ++v) {
        const auto c = static_cast<std::size_t>(coloring.color_of[v]);
        coloring.order[static_cast<std::size_t>(next[c]++)] = static_cast<std::int32_t>(v);
    }
    return coloring;
}

}  // namespace pliant::cloth
