// Colouring of soft-body constraints so that no two constraints of one colour share a vertex: the
// constraints of a colour can be projected in parallel (Gauss–Seidel across colours), with results
// independent of the number of threads.
//
// Two ways:
//   - analytic, on a TetGrid (tet_grid.hpp): cells whose lattice indices agree mod 2 on every axis
//     share no vertex, so tet colour = 5 · (i mod 2 + 2 (j mod 2) + 4 (k mod 2)) + slot (slot =
//     the tet's place 0..4 in its cell): 40 colours. Every grid edge is a cell edge along one axis
//     or a face diagonal (the 5-tet split has no body diagonal); an axis edge along x from lattice
//     (a, b, c) takes colour (a mod 2), likewise y (2 + …) and z (4 + …); a face diagonal in the
//     plane normal to z with lower lattice corner (a, b) takes 6 + (a mod 2) + 2 (b mod 2), normal
//     to y 10 + …, normal to x 14 + …: 18 colours. O(n), no pass over neighbours.
//   - greedy, for any mesh (e.g. TetGen's): constraints in index order each take the smallest
//     colour none of its vertices has yet. Deterministic; at most 256 colours (InvalidInput
//     beyond). O(n · vertices per constraint).
// Within a colour, constraints are in ascending index order (memory locality for cell-ordered
// meshes).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/function_ref.hpp"

namespace pliant::pbd {

struct TetGrid;

struct ConstraintColoring {
    // order[offsets[c] .. offsets[c + 1]) are the constraints of colour c, ascending.
    std::vector<std::int32_t> order;
    std::vector<std::int32_t> offsets{0};

    std::int32_t num_colors() const { return static_cast<std::int32_t>(offsets.size()) - 1; }
    std::span<const std::int32_t> color(std::int32_t c) const {
        const auto begin = static_cast<std::size_t>(offsets[static_cast<std::size_t>(c)]);
        const auto end = static_cast<std::size_t>(offsets[static_cast<std::size_t>(c) + 1]);
        return std::span(order).subspan(begin, end - begin);
    }
};

// Greedy colouring; vertices_of(i) gives the vertices of constraint i, in [0, num_vertices).
ConstraintColoring color_greedy(
    std::int64_t num_constraints, std::int64_t num_vertices,
    FunctionRef<std::span<const std::int32_t>(std::int64_t)> vertices_of);

// Analytic colourings of a grid's tets (40 colours) and of edges between its vertices (18
// colours; InvalidInput for an edge that is neither an axis edge nor a face diagonal of a cell).
ConstraintColoring color_grid_tets(const TetGrid& grid);
ConstraintColoring color_grid_edges(const TetGrid& grid,
                                    std::span<const std::array<std::int32_t, 2>> edges);

}  // namespace pliant::pbd
