#include "pliant/pbd/detail/constraint_layout.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <vector>

#include "pliant/pbd/tet_edges.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "pliant/volume/volume.hpp"
#include "support/tet_grids.hpp"

namespace pliant::pbd::detail {
namespace {

TetGrid grid_over(volume::Dims dims, bool full_box) {
    return test::ball_tet_grid(dims, full_box);
}

std::vector<double> rest_volumes(const TetGrid& grid) {
    std::vector<double> volumes;
    for (const geometry::Tet& t : grid.mesh.tets) {
        const auto p = [&](int m) {
            return vec3_cast<double>(grid.mesh.positions[static_cast<std::size_t>(t[m])]);
        };
        volumes.push_back(geometry::signed_volume(p(0), p(1), p(2), p(3)));
    }
    return volumes;
}

EdgeConstraints grid_edges(const TetGrid& grid) {
    const auto edges = tet_edges(grid.mesh.tets, std::ssize(grid.mesh.positions));
    return layout_edge_constraints(color_grid_edges(grid, edges), edges, grid.mesh.positions,
                                   &grid);
}

TetConstraints grid_tets(const TetGrid& grid) {
    return layout_tet_constraints(color_grid_tets(grid), grid.mesh.tets, rest_volumes(grid), &grid);
}

TEST(ConstraintLayout, EdgesOfAColourAreTheColouringsWithTheirRestLengths) {
    for (const bool full_box : {true, false}) {
        const TetGrid grid = grid_over({12, 10, 22}, full_box);
        const auto edges = tet_edges(grid.mesh.tets, std::ssize(grid.mesh.positions));
        const EdgeConstraints laid = grid_edges(grid);
        const ConstraintColoring& coloring = laid.coloring;
        ASSERT_EQ(laid.vertices.size(), edges.size());
        ASSERT_EQ(laid.rest_lengths, laid.rest_lengths0);
        for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
            // The same set of edges, reordered within the colour.
            std::vector<std::array<std::int32_t, 2>> expected;
            for (const std::int32_t e : coloring.color(c)) {
                expected.push_back(edges[static_cast<std::size_t>(e)]);
            }
            const auto begin =
                laid.vertices.begin() + coloring.offsets[static_cast<std::size_t>(c)];
            std::vector<std::array<std::int32_t, 2>> got(begin, begin + std::ssize(expected));
            std::sort(expected.begin(), expected.end());
            std::sort(got.begin(), got.end());
            EXPECT_EQ(got, expected) << "colour " << c;
        }
        for (std::size_t q = 0; q < laid.vertices.size(); ++q) {
            const auto& [a, b] = laid.vertices[q];
            const auto length = static_cast<float>(
                norm(vec3_cast<double>(grid.mesh.positions[static_cast<std::size_t>(a)]) -
                     vec3_cast<double>(grid.mesh.positions[static_cast<std::size_t>(b)])));
            ASSERT_EQ(laid.rest_lengths0[q], length) << "edge " << q;
        }
    }
}

TEST(ConstraintLayout, TetsInColourOrderWithTheirRestVolumes) {
    for (const bool full_box : {true, false}) {
        const TetGrid grid = grid_over({12, 10, 22}, full_box);
        const std::vector<double> volumes = rest_volumes(grid);
        const TetConstraints laid = grid_tets(grid);
        ASSERT_EQ(laid.rest_volumes, laid.rest_volumes0);
        for (std::size_t k = 0; k < laid.coloring.order.size(); ++k) {
            const auto t = static_cast<std::size_t>(laid.coloring.order[k]);
            ASSERT_EQ(laid.vertices[k], grid.mesh.tets[t]);
            ASSERT_EQ(laid.rest_volumes0[k], static_cast<float>(volumes[t]));
        }
    }
}

TEST(ConstraintLayout, OtherMeshesHaveNoBlocking) {
    const TetGrid grid = grid_over({8, 8, 8}, true);
    const auto edges = tet_edges(grid.mesh.tets, std::ssize(grid.mesh.positions));
    const EdgeConstraints laid_edges =
        layout_edge_constraints(color_grid_edges(grid, edges), edges, grid.mesh.positions, nullptr);
    const TetConstraints laid_tets =
        layout_tet_constraints(color_grid_tets(grid), grid.mesh.tets, rest_volumes(grid), nullptr);
    EXPECT_EQ(laid_edges.blocking.num_layers, 0);
    EXPECT_EQ(laid_tets.blocking.num_layers, 0);
    // Without a grid the edges keep the colouring's order.
    for (std::size_t k = 0; k < laid_edges.coloring.order.size(); ++k) {
        ASSERT_EQ(laid_edges.vertices[k],
                  edges[static_cast<std::size_t>(laid_edges.coloring.order[k])]);
    }
}

}  // namespace
}  // namespace pliant::pbd::detail
