#include "pliant/pbd/detail/lattice_sweep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <iterator>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "pliant/core/parallel.hpp"
#include "pliant/core/simd_dispatch.hpp"
#include "pliant/pbd/detail/grains.hpp"
#include "pliant/pbd/tet_edges.hpp"
#include "pliant/pbd/tet_grid.hpp"
#include "support/grid_constraints.hpp"
#include "support/tet_grids.hpp"

namespace pliant::pbd::detail {
namespace {

// Per colour, the sorted (vertices, rest) pairs of constraints [offsets[c], offsets[c + 1]).
template <typename Constraint>
std::vector<std::vector<std::pair<Constraint, float>>> by_colour(
    const ConstraintColoring& coloring, const std::vector<Constraint>& vertices,
    const std::vector<float>& rest) {
    std::vector<std::vector<std::pair<Constraint, float>>> out;
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        auto& colour = out.emplace_back();
        for (std::int64_t q = coloring.offsets[static_cast<std::size_t>(c)];
             q < coloring.offsets[static_cast<std::size_t>(c) + 1]; ++q) {
            colour.emplace_back(vertices[static_cast<std::size_t>(q)],
                                rest[static_cast<std::size_t>(q)]);
        }
        std::sort(colour.begin(), colour.end());
    }
    return out;
}

// Every run gives its constraints' vertices through the solver order; the runs of a colour cover
// it in order; the layer keys within a colour stay where the blocking expects them.
template <std::size_t K>
void expect_runs_match(const std::vector<std::int32_t>& vertex_of, const TetGrid& grid,
                       const ConstraintColoring& coloring, const LayerBlocking& blocking,
                       const std::vector<std::array<std::int32_t, K>>& vertices,
                       const std::vector<LatticeRun>& runs,
                       const std::vector<std::int64_t>& run_begins,
                       const std::vector<std::int64_t>& run_offsets) {
    ASSERT_EQ(run_offsets.size(), static_cast<std::size_t>(coloring.num_colors()) + 1);
    ASSERT_EQ(run_begins.size(), runs.size());
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        const std::int64_t end = coloring.offsets[static_cast<std::size_t>(c) + 1];
        const std::int64_t r0 = run_offsets[static_cast<std::size_t>(c)];
        const std::int64_t r1 = run_offsets[static_cast<std::size_t>(c) + 1];
        ASSERT_LT(r0, r1) << "colour " << c;
        EXPECT_EQ(runs[static_cast<std::size_t>(r0)].begin, begin);
        for (std::int64_t r = r0; r < r1; ++r) {
            const LatticeRun& run = runs[static_cast<std::size_t>(r)];
            EXPECT_EQ(run_begins[static_cast<std::size_t>(r)], run.begin);
            const std::int64_t run_end =
                r + 1 < r1 ? runs[static_cast<std::size_t>(r) + 1].begin : end;
            ASSERT_LT(run.begin, run_end);
            for (std::int64_t q = run.begin; q < run_end; ++q) {
                for (std::size_t m = 0; m < K; ++m) {
                    ASSERT_EQ(vertex_of[static_cast<std::size_t>(run.first[m] + q - run.begin)],
                              vertices[static_cast<std::size_t>(q)][m])
                        << "colour " << c << " run " << r << " constraint " << q;
                }
            }
        }
        // Layer keys: constraints [layer_begin[z], layer_begin[z + 1]) of the colour have key z.
        ASSERT_GT(blocking.num_layers, 0);
        for (std::int64_t z = 0; z < blocking.num_layers; ++z) {
            const std::int64_t* layer_begin =
                blocking.layer_begin.data() +
                static_cast<std::size_t>(c) * static_cast<std::size_t>(blocking.num_layers + 1);
            for (std::int64_t q = begin + layer_begin[z]; q < begin + layer_begin[z + 1]; ++q) {
                std::int32_t key = grid.vertex_lattice[static_cast<std::size_t>(
                    vertices[static_cast<std::size_t>(q)][0])][2];
                for (std::size_t m = 1; m < K; ++m) {
                    key = std::min(key, grid.vertex_lattice[static_cast<std::size_t>(
                                            vertices[static_cast<std::size_t>(q)][m])][2]);
                }
                ASSERT_EQ(key, z) << "colour " << c << " constraint " << q;
            }
        }
    }
}

TEST(LatticeSweep, RunsGiveEveryConstraintsVerticesInTheSolverOrder) {
    for (const bool full_box : {true, false}) {
        const TetGrid grid = test::ball_tet_grid({40, 36, 30}, full_box);
        const test::GridConstraints plain = test::grid_constraints(grid);
        test::GridConstraints laid = test::grid_constraints(grid);
        const LatticeSweep sweep = build_lattice_sweep(grid, laid.edges, laid.tets);
        // A permutation of the vertices.
        std::vector<std::int32_t> sorted = sweep.vertex_of;
        std::sort(sorted.begin(), sorted.end());
        for (std::size_t v = 0; v < sorted.size(); ++v) {
            ASSERT_EQ(sorted[v], static_cast<std::int32_t>(v));
        }
        ASSERT_EQ(sorted.size(), grid.mesh.positions.size());
        // The same constraints with the same rest data in every colour.
        EXPECT_EQ(by_colour(laid.edges.coloring, laid.edges.vertices, laid.edges.rest_lengths0),
                  by_colour(plain.edges.coloring, plain.edges.vertices, plain.edges.rest_lengths0));
        EXPECT_EQ(laid.edges.rest_lengths, laid.edges.rest_lengths0);
        EXPECT_EQ(by_colour(laid.tets.coloring, laid.tets.vertices, laid.tets.rest_volumes0),
                  by_colour(plain.tets.coloring, plain.tets.vertices, plain.tets.rest_volumes0));
        EXPECT_EQ(laid.tets.rest_volumes, laid.tets.rest_volumes0);
        expect_runs_match(sweep.vertex_of, grid, laid.edges.coloring, laid.edges.blocking,
                          laid.edges.vertices, sweep.edge_runs, sweep.edge_run_begins,
                          sweep.edge_run_offsets);
        expect_runs_match(sweep.vertex_of, grid, laid.tets.coloring, laid.tets.blocking,
                          laid.tets.vertices, sweep.tet_runs, sweep.tet_run_begins,
                          sweep.tet_run_offsets);
        // Runs are long enough for the 8-wide kernels: on the ball, whose rows of 20 cells hold
        // up to 10 of a parity, more than 4 constraints per run on average.
        EXPECT_GT(laid.tets.vertices.size(), 4 * sweep.tet_runs.size());
        EXPECT_GT(laid.edges.vertices.size(), 4 * sweep.edge_runs.size());
    }
}

// The lanes (LatticeSweep): lane_begin covers every colour in order of (layer key, lane); at
// every vertex the constraints holding it have lanes that do not decrease with their colour (so a
// lane's slab depends only on lanes ≤ it); both lanes hold a fair share of the constraints.
template <std::size_t K>
void expect_lanes_ordered(const TetGrid& grid, const ConstraintColoring& coloring,
                          const LayerBlocking& blocking,
                          const std::vector<std::array<std::int32_t, K>>& vertices,
                          const std::vector<std::int64_t>& lane_begin) {
    const std::int64_t per_colour = blocking.num_layers * SWEEP_LANES + 1;
    ASSERT_EQ(lane_begin.size(), static_cast<std::size_t>(coloring.num_colors() * per_colour));
    std::vector<std::int64_t> lane_of(vertices.size(), -1);
    std::vector<std::int64_t> lane_count(SWEEP_LANES, 0);
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        const std::int64_t* entry = lane_begin.data() + static_cast<std::size_t>(c * per_colour);
        ASSERT_EQ(entry[0], 0);
        ASSERT_EQ(entry[per_colour - 1], coloring.offsets[static_cast<std::size_t>(c) + 1] - begin);
        for (std::int64_t slot = 0; slot + 1 < per_colour; ++slot) {
            ASSERT_LE(entry[slot], entry[slot + 1]);
            for (std::int64_t q = begin + entry[slot]; q < begin + entry[slot + 1]; ++q) {
                std::int32_t key = grid.vertex_lattice[static_cast<std::size_t>(
                    vertices[static_cast<std::size_t>(q)][0])][2];
                for (std::size_t m = 1; m < K; ++m) {
                    key = std::min(key, grid.vertex_lattice[static_cast<std::size_t>(
                                            vertices[static_cast<std::size_t>(q)][m])][2]);
                }
                ASSERT_EQ(key, slot / SWEEP_LANES) << "colour " << c << " constraint " << q;
                lane_of[static_cast<std::size_t>(q)] = slot % SWEEP_LANES;
                ++lane_count[static_cast<std::size_t>(slot % SWEEP_LANES)];
            }
        }
    }
    // Per vertex, (colour, lane) of the constraints holding it.
    std::vector<std::vector<std::pair<std::int32_t, std::int64_t>>> at(grid.vertex_lattice.size());
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        for (std::int64_t q = coloring.offsets[static_cast<std::size_t>(c)];
             q < coloring.offsets[static_cast<std::size_t>(c) + 1]; ++q) {
            for (const std::int32_t v : vertices[static_cast<std::size_t>(q)]) {
                at[static_cast<std::size_t>(v)].emplace_back(c,
                                                             lane_of[static_cast<std::size_t>(q)]);
            }
        }
    }
    for (std::size_t v = 0; v < at.size(); ++v) {
        std::sort(at[v].begin(), at[v].end());
        for (std::size_t i = 1; i < at[v].size(); ++i) {
            ASSERT_LE(at[v][i - 1].second, at[v][i].second) << "vertex " << v;
        }
    }
    const auto total = static_cast<double>(vertices.size());
    for (const std::int64_t n : lane_count) {
        EXPECT_GT(static_cast<double>(n), 0.3 * total);
    }
}

TEST(LatticeSweep, LanesFollowTheColourOrderAtEveryVertex) {
    for (const bool full_box : {true, false}) {
        const TetGrid grid = test::ball_tet_grid({40, 36, 30}, full_box);
        test::GridConstraints laid = test::grid_constraints(grid);
        const LatticeSweep sweep = build_lattice_sweep(grid, laid.edges, laid.tets);
        expect_lanes_ordered(grid, laid.edges.coloring, laid.edges.blocking, laid.edges.vertices,
                             sweep.edge_lane_begin);
        expect_lanes_ordered(grid, laid.tets.coloring, laid.tets.blocking, laid.tets.vertices,
                             sweep.tet_lane_begin);
    }
}

TEST(LatticeSweep, ProjectsBitwiseAsTheColourSweep) {
    if (!pliant::has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this machine";
    }
    // Positions moved at random by up to 40 % of a cell, some vertices with w = 0: the lattice
    // sweep against the plain layout's scalar / SSE sweep, the same bits and the same tets at risk
    // (compared as vertex sets: the two layouts order a colour differently).
    const TetGrid grid = test::ball_tet_grid({40, 36, 30}, false);
    test::GridConstraints plain = test::grid_constraints(grid);
    test::GridConstraints laid = test::grid_constraints(grid);
    LatticeSweep sweep = build_lattice_sweep(grid, laid.edges, laid.tets);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> jitter(-0.8f, 0.8f);
    std::vector<Float4> x0;
    for (std::size_t v = 0; v < grid.mesh.positions.size(); ++v) {
        const Vec3f& p = grid.mesh.positions[v];
        x0.push_back({p.x + jitter(rng), p.y + jitter(rng), p.z + jitter(rng),
                      v % 11 == 0 ? 0.0f : 1.0f + 0.1f * static_cast<float>(v % 5)});
    }
    const ConstraintStiffness edge_k{20.0f, 0.0f};
    const ConstraintStiffness tet_k{1.25f, 0.001f};
    for (const int threads : {1, 2}) {
        set_num_threads(threads);
        std::vector<Float4> expected = x0;
        std::vector<std::uint8_t> expected_risk(plain.tets.vertices.size(), 0);
        std::vector<std::uint8_t> expected_colours(
            static_cast<std::size_t>(plain.tets.coloring.num_colors()), 0);
        project_edges(expected.data(), plain.edges, edge_k, false);
        project_tets(expected.data(), plain.tets, tet_k, false, expected_risk, expected_colours);
        std::vector<Float4> got = x0;
        std::vector<std::uint8_t> got_risk(laid.tets.vertices.size(), 0);
        std::vector<std::uint8_t> got_colours(expected_colours.size(), 0);
        project_lattice(got.data(), sweep, laid.edges, laid.tets, edge_k, tet_k, got_risk,
                        got_colours);
        std::size_t differing = 0;
        for (std::size_t v = 0; v < got.size(); ++v) {
            differing += std::memcmp(&got[v], &expected[v], sizeof(Float4)) != 0 ? 1 : 0;
        }
        EXPECT_EQ(differing, 0u) << threads << " threads";
        EXPECT_EQ(got_colours, expected_colours);
        const auto flagged = [](const TetConstraints& tets, const std::vector<std::uint8_t>& risk) {
            std::set<geometry::Tet> out;
            for (std::size_t q = 0; q < risk.size(); ++q) {
                if (risk[q] != 0) {
                    out.insert(tets.vertices[q]);
                }
            }
            return out;
        };
        const std::set<geometry::Tet> expected_flagged = flagged(plain.tets, expected_risk);
        EXPECT_GT(expected_flagged.size(), 0u);  // the jitter puts tets at risk
        EXPECT_EQ(flagged(laid.tets, got_risk), expected_flagged);
    }
    set_num_threads(0);
}

}  // namespace
}  // namespace pliant::pbd::detail
