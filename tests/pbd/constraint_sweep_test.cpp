#include "pliant/pbd/detail/constraint_sweep.hpp"

#include <gtest/gtest.h>

#include <array>
#include <iterator>
#include <string>
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

// Runs sweep_colours and returns "" when it visited every constraint once and, at every vertex,
// the constraints holding it in the order of their colours (the plain sweep's order, which the
// layer blocking must keep); else what went wrong first.
template <typename Constraint>
std::string check_sweep_order(const LayerBlocking& blocking, const ConstraintColoring& coloring,
                              const std::vector<Constraint>& constraints, std::size_t num_vertices,
                              std::int64_t& num_ranges) {
    std::vector<int> visits(constraints.size(), 0);
    std::vector<std::int32_t> last_colour(num_vertices, -1);
    std::string problem;
    num_ranges = 0;
    sweep_colours(blocking, coloring, [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
        ++num_ranges;
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        for (std::int64_t q = begin + lo; q < begin + hi; ++q) {
            ++visits[static_cast<std::size_t>(q)];
            for (const std::int32_t v : constraints[static_cast<std::size_t>(q)]) {
                std::int32_t& last = last_colour[static_cast<std::size_t>(v)];
                if (last > c && problem.empty()) {
                    problem = "vertex " + std::to_string(v) + ": colour " + std::to_string(c) +
                              " after colour " + std::to_string(last);
                }
                last = std::max(last, c);
            }
        }
    });
    for (std::size_t q = 0; q < visits.size() && problem.empty(); ++q) {
        if (visits[q] != 1) {
            problem = "constraint " + std::to_string(q) + " visited " + std::to_string(visits[q]) +
                      " times";
        }
    }
    return problem;
}

TEST(ConstraintSweep, BlockedSweepKeepsTheColourOrderAtEveryVertex) {
    for (const bool full_box : {true, false}) {
        // 6 × 5 × 21 cells: several slabs of LAYERS_PER_SLAB layers and a partial last one.
        const TetGrid grid = grid_over({12, 10, 42}, full_box);
        const auto edges = tet_edges(grid.mesh.tets, std::ssize(grid.mesh.positions));
        const EdgeConstraints laid_edges = layout_edge_constraints(
            color_grid_edges(grid, edges), edges, grid.mesh.positions, &grid);
        const std::vector<double> volumes(grid.mesh.tets.size(), 1.0);
        const TetConstraints laid_tets =
            layout_tet_constraints(color_grid_tets(grid), grid.mesh.tets, volumes, &grid);
        ASSERT_GT(laid_edges.blocking.num_layers, 2 * LAYERS_PER_SLAB);
        ASSERT_GT(laid_tets.blocking.num_layers, 2 * LAYERS_PER_SLAB);
        EXPECT_GT(laid_edges.blocking.max_skew, 0);  // else the ordering is not at stake
        std::int64_t num_ranges = 0;
        EXPECT_EQ(check_sweep_order(laid_edges.blocking, laid_edges.coloring, laid_edges.vertices,
                                    grid.mesh.num_vertices(), num_ranges),
                  "")
            << "edges, full box " << full_box;
        EXPECT_GT(num_ranges, laid_edges.coloring.num_colors());  // it did block
        EXPECT_EQ(check_sweep_order(laid_tets.blocking, laid_tets.coloring, laid_tets.vertices,
                                    grid.mesh.num_vertices(), num_ranges),
                  "")
            << "tets, full box " << full_box;
        EXPECT_GT(num_ranges, laid_tets.coloring.num_colors());

        // The check can fail: without the skews, a later colour's slab overtakes an earlier
        // colour at a shared vertex.
        LayerBlocking unskewed = laid_edges.blocking;
        std::fill(unskewed.skew.begin(), unskewed.skew.end(), 0);
        unskewed.max_skew = 0;
        EXPECT_NE(check_sweep_order(unskewed, laid_edges.coloring, laid_edges.vertices,
                                    grid.mesh.num_vertices(), num_ranges),
                  "");
    }
}

TEST(ConstraintSweep, WithoutBlockingEachColourIsOneRangeInOrder) {
    const ConstraintColoring coloring{.order = {0, 2, 4, 1, 3, 5}, .offsets = {0, 3, 5, 6}};
    std::vector<std::array<std::int64_t, 3>> ranges;
    sweep_colours(LayerBlocking{}, coloring, [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
        ranges.push_back({c, lo, hi});
    });
    const std::vector<std::array<std::int64_t, 3>> expected{{0, 0, 3}, {1, 0, 2}, {2, 0, 1}};
    EXPECT_EQ(ranges, expected);
}

}  // namespace
}  // namespace pliant::pbd::detail
