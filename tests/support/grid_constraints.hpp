// A tet grid's constraints as SoftBody lays them out (pbd/detail/constraint_layout.hpp): its
// edges and tets coloured with the grid colourings, rest lengths and volumes from the grid's
// positions (volumes in double), with their layer blocking. For the pbd layout and sweep tests.
#pragma once

#include <vector>

#include "pliant/geometry/tet_mesh.hpp"
#include "pliant/pbd/constraint_coloring.hpp"
#include "pliant/pbd/detail/constraint_layout.hpp"
#include "pliant/pbd/tet_edges.hpp"
#include "pliant/pbd/tet_grid.hpp"

namespace pliant::test {

struct GridConstraints {
    pbd::detail::EdgeConstraints edges;
    pbd::detail::TetConstraints tets;
};

inline GridConstraints grid_constraints(const pbd::TetGrid& grid) {
    const auto edges = pbd::tet_edges(grid.mesh.tets, std::ssize(grid.mesh.positions));
    std::vector<double> volumes;
    for (const geometry::Tet& t : grid.mesh.tets) {
        const auto p = [&](int m) {
            return vec3_cast<double>(grid.mesh.positions[static_cast<std::size_t>(t[m])]);
        };
        volumes.push_back(geometry::signed_volume(p(0), p(1), p(2), p(3)));
    }
    return {pbd::detail::layout_edge_constraints(pbd::color_grid_edges(grid, edges), edges,
                                                 grid.mesh.positions, &grid),
            pbd::detail::layout_tet_constraints(pbd::color_grid_tets(grid), grid.mesh.tets, volumes,
                                                &grid)};
}

}  // namespace pliant::test
