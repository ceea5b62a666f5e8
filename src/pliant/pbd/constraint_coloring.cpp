#include "pliant/pbd/constraint_coloring.hpp"

#include <bit>
#include <string>

#include "pliant/core/error.hpp"
#include "pliant/pbd/tet_grid.hpp"

namespace pliant::pbd {
namespace {

constexpr int MAX_COLORS = 256;
constexpr int MASK_WORDS = MAX_COLORS / 64;

// Counting sort of constraints by colour: ascending constraint order within each colour.
ConstraintColoring group_by_color(const std::vector<std::int32_t>& color_of, int num_colors) {
    ConstraintColoring coloring;
    coloring.offsets.assign(static_cast<std::size_t>(num_colors) + 1, 0);
    for (const std::int32_t c : color_of) {
        ++coloring.offsets[static_cast<std::size_t>(c) + 1];
    }
    for (std::size_t c = 0; c < static_cast<std::size_t>(num_colors); ++c) {
        coloring.offsets[c + 1] += coloring.offsets[c];
    }
    // Drop trailing empty colours (non-full grids may lack some).
    std::vector<std::int32_t> fill(coloring.offsets.begin(), coloring.offsets.end() - 1);
    coloring.order.resize(color_of.size());
    for (std::size_t i = 0; i < color_of.size(); ++i) {
        coloring.order[static_cast<std::size_t>(fill[static_cast<std::size_t>(color_of[i])]++)] =
            static_cast<std::int32_t>(i);
    }
    // Remove empty colours so that every colour holds work.
    std::vector<std::int32_t> offsets{0};
    for (std::size_t c = 0; c < static_cast<std::size_t>(num_colors); ++c) {
        if (coloring.offsets[c + 1] > coloring.offsets[c]) {
            offsets.push_back(coloring.offsets[c + 1]);
        }
    }
    coloring.offsets = std::move(offsets);
    return coloring;
}

}  // namespace

ConstraintColoring color_greedy(
    std::int64_t num_constraints, std::int64_t num_vertices,
    FunctionRef<std::span<const std::int32_t>(std::int64_t)> vertices_of) {
    // used[v]: bit c set when a constraint of colour c holds vertex v.
    std::vector<std::array<std::uint64_t, MASK_WORDS>> used(static_cast<std::size_t>(num_vertices),
                                                            {0, 0, 0, 0});
    std::vector<std::int32_t> color_of(static_cast<std::size_t>(num_constraints));
    int num_colors = 0;
    for (std::int64_t i = 0; i < num_constraints; ++i) {
        const std::span<const std::int32_t> vertices = vertices_of(i);
        std::array<std::uint64_t, MASK_WORDS> taken{0, 0, 0, 0};
        for (const std::int32_t v : vertices) {
            for (int w = 0; w < MASK_WORDS; ++w) {
                taken[static_cast<std::size_t>(w)] |=
                    used[static_cast<std::size_t>(v)][static_cast<std::size_t>(w)];
            }
        }
        int color = -1;
        for (int w = 0; w < MASK_WORDS && color < 0; ++w) {
            const std::uint64_t free = ~taken[static_cast<std::size_t>(w)];
            if (free != 0) {
                color = 64 * w + std::countr_zero(free);
            }
        }
        if (color < 0) {
            throw InvalidInput("pbd::color_greedy: constraint " + std::to_string(i) +
                               " needs more than " + std::to_string(MAX_COLORS) +
                               " colours (a vertex in too many constraints)");
        }
        for (const std::int32_t v : vertices) {
            used[static_cast<std::size_t>(v)][static_cast<std::size_t>(color / 64)] |=
                std::uint64_t{1} << (color % 64);
        }
        color_of[static_cast<std::size_t>(i)] = color;
        num_colors = std::max(num_colors, color + 1);
    }
    return group_by_color(color_of, num_colors);
}

ConstraintColoring color_grid_tets(const TetGrid& grid) {
    const std::int64_t nx = grid.cells[0];
    const std::int64_t ny = grid.cells[1];
    std::vector<std::int32_t> color_of(grid.tet_cell.size());
    for (std::size_t t = 0; t < grid.tet_cell.size(); ++t) {
        const std::int64_t cell = grid.tet_cell[t];
        const std::int64_t i = cell % nx;
        const std::int64_t j = (cell / nx) % ny;
        const std::int64_t k = cell / (nx * ny);
        const auto parity = static_cast<std::int32_t>((i & 1) + 2 * (j & 1) + 4 * (k & 1));
        // A cell's 5 tets are consecutive from a multiple of 5 (tet_grid.hpp).
        color_of[t] = 5 * parity + static_cast<std::int32_t>(t % 5);
    }
    return group_by_color(color_of, 40);
}

ConstraintColoring color_grid_edges(const TetGrid& grid,
                                    std::span<const std::array<std::int32_t, 2>> edges) {
    std::vector<std::int32_t> color_of(edges.size());
    for (std::size_t e = 0; e < edges.size(); ++e) {
        const auto& la = grid.vertex_lattice[static_cast<std::size_t>(edges[e][0])];
        const auto& lb = grid.vertex_lattice[static_cast<std::size_t>(edges[e][1])];
        std::array<std::int32_t, 3> lo{};
        int moved = 0;
        int fixed_axis = -1;
        int moved_axis = -1;
        bool is_cell_edge = true;
        for (std::size_t axis = 0; axis < 3; ++axis) {
            const std::int32_t d = lb[axis] - la[axis];
            lo[axis] = std::min(la[axis], lb[axis]);
            if (d == 0) {
                fixed_axis = static_cast<int>(axis);
            } else if (d == 1 || d == -1) {
                ++moved;
                moved_axis = static_cast<int>(axis);
            } else {
                is_cell_edge = false;
            }
        }
        if (!is_cell_edge || moved == 0 || moved == 3) {
            throw InvalidInput("pbd::color_grid_edges: edge " + std::to_string(e) + " (" +
                               std::to_string(edges[e][0]) + ", " + std::to_string(edges[e][1]) +
                               ") is neither an axis edge nor a face diagonal of a cell");
        }
        if (moved == 1) {
            // Axis edges along one axis share a vertex only when on one lattice line, adjacent.
            color_of[e] = 2 * moved_axis + (lo[static_cast<std::size_t>(moved_axis)] & 1);
        } else {
            // Face diagonals in one lattice plane share a vertex only in neighbouring faces.
            const int u = (fixed_axis + 1) % 3;
            const int v = (fixed_axis + 2) % 3;
            color_of[e] = 6 + 4 * (2 - fixed_axis) + (lo[static_cast<std::size_t>(u)] & 1) +
                          2 * (lo[static_cast<std::size_t>(v)] & 1);
        }
    }
    return group_by_color(color_of, 18);
}

}  // namespace pliant::pbd
