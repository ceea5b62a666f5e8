#include "pliant/cloth/constraint_coloring.hpp"

#include <fmt/format.h>

#include <bit>

#include "pliant/core/error.hpp"

namespace pliant::cloth {

ConstraintColoring color_constraints(
    std::int64_t num_constraints, std::int64_t num_vertices,
    FunctionRef<std::span<const std::int32_t>(std::int64_t)> vertices_of) {
    // used[v]: bit c set when a constraint of colour c touches v.
    std::vector<std::uint64_t> used(static_cast<std::size_t>(num_vertices), 0);
    std::vector<std::int32_t> color_of(static_cast<std::size_t>(num_constraints));
    std::vector<std::int32_t> count;
    for (std::int64_t i = 0; i < num_constraints; ++i) {
        std::uint64_t taken = 0;
        for (const std::int32_t v : vertices_of(i)) {
            taken |= used[static_cast<std::size_t>(v)];
        }
        if (taken == ~std::uint64_t{0}) {
            throw InvalidInput(fmt::format(
                "constraint colouring: constraint {} touches vertices already in 64 colours, "
                "expected at most 63 constraints per vertex",
                i));
        }
        const int c = std::countr_one(taken);
        for (const std::int32_t v : vertices_of(i)) {
            used[static_cast<std::size_t>(v)] |= std::uint64_t{1} << c;
        }
        color_of[static_cast<std::size_t>(i)] = c;
        if (static_cast<std::size_t>(c) >= count.size()) {
            count.resize(static_cast<std::size_t>(c) + 1, 0);
        }
        ++count[static_cast<std::size_t>(c)];
    }
    ConstraintColoring coloring;
    coloring.offsets.assign(count.size() + 1, 0);
    for (std::size_t c = 0; c < count.size(); ++c) {
        coloring.offsets[c + 1] = coloring.offsets[c] + count[c];
    }
    coloring.order.resize(static_cast<std::size_t>(num_constraints));
    std::vector<std::int32_t> next(coloring.offsets.begin(), coloring.offsets.end() - 1);
    for (std::int64_t i = 0; i < num_constraints; ++i) {
        const auto c = static_cast<std::size_t>(color_of[static_cast<std::size_t>(i)]);
        coloring.order[static_cast<std::size_t>(next[c]++)] = static_cast<std::int32_t>(i);
    }
    return coloring;
}

ColoredEdges color_edges(std::span<const std::array<std::int32_t, 2>> edges,
                         std::span<const double> rest, std::int64_t num_vertices) {
    ColoredEdges colored;
    colored.colors = color_constraints(
        static_cast<std::int64_t>(edges.size()), num_vertices, [&](std::int64_t i) {
            return std::span<const std::int32_t>(edges[static_cast<std::size_t>(i)]);
        });
    for (const std::int32_t i : colored.colors.order) {
        const auto k = static_cast<std::size_t>(i);
        colored.p.push_back(edges[k][0]);
        colored.q.push_back(edges[k][1]);
        colored.rest.push_back(rest[k]);
    }
    return colored;
}

ColoredHinges color_hinges(std::span<const std::array<std::int32_t, 4>> hinges,
                           std::int64_t num_vertices) {
    ColoredHinges colored;
    colored.colors = color_constraints(
        static_cast<std::int64_t>(hinges.size()), num_vertices, [&](std::int64_t i) {
            return std::span<const std::int32_t>(hinges[static_cast<std::size_t>(i)]);
        });
    for (const std::int32_t i : colored.colors.order) {
        for (std::size_t k = 0; k < 4; ++k) {
            colored.v[k].push_back(hinges[static_cast<std::size_t>(i)][k]);
        }
    }
    return colored;
}

}  // namespace pliant::cloth
