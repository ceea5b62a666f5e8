// Greedy colouring of a mesh's vertices so that no two vertices of one colour share an element
// (an edge, or a bending hinge's four vertices): the vertices of a colour can then be updated in
// parallel by a per-vertex solver that reads its neighbours (Vertex Block Descent: Chen, Macklin,
// Bi, Liu, Kim, "Vertex Block Descent", SIGGRAPH 2024, §3.4), Gauss-Seidel across colours, and
// the result does not depend on the number of threads.
//
//   const VertexColoring coloring = color_vertices(num_vertices, elements);
//   for (std::int32_t c = 0; c < coloring.num_colors(); ++c) parallel_for(coloring.color(c) …);
//
// Deterministic: vertices are visited in index order and each takes the smallest colour not used
// by a vertex it shares an element with. Cost O(Σ over elements of (vertices per element)²).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace pliant::cloth {

struct VertexColoring {
    // order[offsets[c] .. offsets[c + 1]) are the vertices of colour c, ascending.
    std::vector<std::int32_t> order;
    std::vector<std::int32_t> offsets;
    // Per vertex, its colour.
    std::vector<std::int32_t> color_of;

    std::int32_t num_colors() const { return static_cast<std::int32_t>(offsets.size()) - 1; }
    std::span<const std::int32_t> color(std::int32_t c) const {
        return std::span(order).subspan(
            static_cast<std::size_t>(offsets[static_cast<std::size_t>(c)]),
            static_cast<std::size_t>(offsets[static_cast<std::size_t>(c) + 1] -
                                     offsets[static_cast<std::size_t>(c)]));
    }
};

// elements: the vertex lists of the elements (edges, hinges, …) flattened, element k being
// vertices[element_offsets[k] .. element_offsets[k + 1]) (element_offsets has #elements + 1
// entries, starting at 0). Vertices in [0, num_vertices); InvalidInput otherwise.
VertexColoring color_vertices(std::int64_t num_vertices, std::span<const std::int32_t> vertices,
                              std::span<const std::int32_t> element_offsets);

}  // namespace pliant::cloth
