#include "pliant/pbd/constraint_coloring.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "pliant/core/error.hpp"
#include "pliant/pbd/tet_edges.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/volume.hpp"
#include "support/tet_grids.hpp"

namespace pliant::pbd {
namespace {

// Every constraint exactly once, ascending within a colour, no colour empty, and no two
// constraints of a colour sharing a vertex.
template <typename Constraint>
void expect_valid(const ConstraintColoring& coloring, const std::vector<Constraint>& constraints,
                  std::size_t num_vertices) {
    ASSERT_EQ(coloring.order.size(), constraints.size());
    std::vector<int> seen(constraints.size(), 0);
    std::vector<std::int32_t> owner(num_vertices, -1);
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        const auto color = coloring.color(c);
        EXPECT_FALSE(color.empty()) << c;
        EXPECT_TRUE(std::is_sorted(color.begin(), color.end())) << c;
        for (const std::int32_t i : color) {
            ++seen[static_cast<std::size_t>(i)];
            for (const std::int32_t v : constraints[static_cast<std::size_t>(i)]) {
                EXPECT_NE(owner[static_cast<std::size_t>(v)], c)
                    << "colour " << c << " has two constraints on vertex " << v;
                owner[static_cast<std::size_t>(v)] = c;
            }
        }
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
}

TetGrid grid_over(volume::Dims dims, bool full_box, int cell_voxels) {
    return test::ball_tet_grid(dims, full_box, cell_voxels);
}

TEST(ConstraintColoring, GridColouringsAreValid) {
    for (const bool full : {true, false}) {
        const TetGrid grid = grid_over({13, 10, 9}, full, 2);
        ASSERT_GT(grid.mesh.num_tets(), 0u);
        const auto edges =
            tet_edges(grid.mesh.tets, static_cast<std::int64_t>(grid.mesh.num_vertices()));
        const ConstraintColoring tet_colors = color_grid_tets(grid);
        const ConstraintColoring edge_colors = color_grid_edges(grid, edges);
        if (full) {
            EXPECT_EQ(tet_colors.num_colors(), 40);
            EXPECT_EQ(edge_colors.num_colors(), 18);
        }
        expect_valid(tet_colors, grid.mesh.tets, grid.mesh.num_vertices());
        expect_valid(edge_colors, edges, grid.mesh.num_vertices());
    }
}

TEST(ConstraintColoring, GreedyColouringIsValidAndDeterministic) {
    const TetGrid grid = grid_over({12, 12, 12}, false, 3);
    const auto nv = static_cast<std::int64_t>(grid.mesh.num_vertices());
    const auto of_tet = [&](std::int64_t t) {
        return std::span<const std::int32_t>(grid.mesh.tets[static_cast<std::size_t>(t)]);
    };
    const ConstraintColoring a =
        color_greedy(static_cast<std::int64_t>(grid.mesh.num_tets()), nv, of_tet);
    const ConstraintColoring b =
        color_greedy(static_cast<std::int64_t>(grid.mesh.num_tets()), nv, of_tet);
    expect_valid(a, grid.mesh.tets, grid.mesh.num_vertices());
    EXPECT_EQ(a.order, b.order);
    EXPECT_EQ(a.offsets, b.offsets);
    const auto edges = tet_edges(grid.mesh.tets, nv);
    const ConstraintColoring e =
        color_greedy(static_cast<std::int64_t>(edges.size()), nv, [&](std::int64_t i) {
            return std::span<const std::int32_t>(edges[static_cast<std::size_t>(i)]);
        });
    expect_valid(e, edges, grid.mesh.num_vertices());
}

TEST(ConstraintColoring, EmptyInputHasNoColours) {
    const ConstraintColoring c =
        color_greedy(0, 0, [](std::int64_t) { return std::span<const std::int32_t>(); });
    EXPECT_EQ(c.num_colors(), 0);
    EXPECT_TRUE(c.order.empty());
}

TEST(ConstraintColoring, GridEdgeColouringRejectsNonGridEdges) {
    const TetGrid grid = grid_over({4, 4, 4}, true, 2);
    // Vertex 0 is lattice (0, 0, 0), the last vertex (2, 2, 2): not a cell edge.
    const std::vector<std::array<std::int32_t, 2>> edges{
        {0, static_cast<std::int32_t>(grid.mesh.num_vertices()) - 1}};
    EXPECT_THROW(color_grid_edges(grid, edges), InvalidInput);
}

TEST(TetEdges, OneCellHasTwelveCubeEdgesAndSixDiagonals) {
    const TetGrid grid = grid_over({2, 2, 2}, true, 2);
    const auto edges = tet_edges(grid.mesh.tets, 8);
    EXPECT_EQ(edges.size(), 18u);
    EXPECT_TRUE(std::is_sorted(edges.begin(), edges.end()));
    std::set<std::array<std::int32_t, 2>> unique(edges.begin(), edges.end());
    EXPECT_EQ(unique.size(), edges.size());
    for (const auto& e : edges) {
        EXPECT_LT(e[0], e[1]);
    }
}

}  // namespace
}  // namespace pliant::pbd
