// Greedy colouring of constraints so that no two constraints of one colour share a vertex: the
// constraints of a colour can then be projected in parallel (Gauss-Seidel between colours, Jacobi-
// free within), and the result does not depend on the number of threads.
//
//   const ConstraintColoring coloring = color_constraints(vertices_of, num_constraints,
//   num_vertices); for (const auto& color : coloring.colors()) parallel_for(color.size(), …);
//
// Deterministic: constraints are visited in index order and each takes the smallest colour not
// used by one of its vertices. At most 64 colours (a vertex in more than 63 constraints of the
// same kind throws InvalidInput). Cost O(constraints × vertices per constraint).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/function_ref.hpp"

namespace pliant::cloth {

struct ConstraintColoring {
    // order[offsets[c] .. offsets[c + 1]) are the constraints of colour c, ascending.
    std::vector<std::int32_t> order;
    std::vector<std::int32_t> offsets;

    std::int32_t num_colors() const { return static_cast<std::int32_t>(offsets.size()) - 1; }
    std::span<const std::int32_t> color(std::int32_t c) const {
        return std::span(order).subspan(
            static_cast<std::size_t>(offsets[static_cast<std::size_t>(c)]),
            static_cast<std::size_t>(offsets[static_cast<std::size_t>(c) + 1] -
                                     offsets[static_cast<std::size_t>(c)]));
    }
};

// vertices_of(i) gives the vertices of constraint i (indices in [0, num_vertices)).
ConstraintColoring color_constraints(
    std::int64_t num_constraints, std::int64_t num_vertices,
    FunctionRef<std::span<const std::int32_t>(std::int64_t)> vertices_of);

// Two-vertex constraints (p–q with a rest length: the solver's stretch constraints, the strain
// limits) coloured, and laid out as the kernels read them: columns in colour order, colour c
// in [colors.offsets[c], colors.offsets[c + 1]).
struct ColoredEdges {
    ConstraintColoring colors;
    std::vector<std::int32_t> p;
    std::vector<std::int32_t> q;
    std::vector<double> rest;
};

// edges[i] with rest length rest[i] (same size), coloured by color_constraints.
ColoredEdges color_edges(std::span<const std::array<std::int32_t, 2>> edges,
                         std::span<const double> rest, std::int64_t num_vertices);

// Four-vertex constraints (hinges: x0, x1, then the shared edge x2-x3, as in dihedral.hpp)
// coloured, their vertices laid out as four columns in colour order; a caller lays out its own
// per-hinge data by colors.order likewise.
struct ColoredHinges {
    ConstraintColoring colors;
    std::array<std::vector<std::int32_t>, 4> v;
    std::size_t size() const { return colors.order.size(); }
};

ColoredHinges color_hinges(std::span<const std::array<std::int32_t, 4>> hinges,
                           std::int64_t num_vertices);

}  // namespace pliant::cloth
