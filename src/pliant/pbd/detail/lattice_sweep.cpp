#include "pliant/pbd/detail/lattice_sweep.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <numeric>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"

namespace pliant::pbd::detail {
namespace {

// The solver order (lattice_sweep.hpp): vertex_of (#V) and its inverse, solver_index.
void solver_order(const TetGrid& grid, std::vector<std::int32_t>& vertex_of,
                  std::vector<std::int32_t>& solver_index) {
    const auto nv = static_cast<std::int64_t>(grid.vertex_lattice.size());
    const std::int64_t lx = std::int64_t{grid.cells[0]} + 1;
    const std::int64_t ly = std::int64_t{grid.cells[1]} + 1;
    std::vector<std::int64_t> key(static_cast<std::size_t>(nv));
    for (std::int64_t v = 0; v < nv; ++v) {
        const auto& l = grid.vertex_lattice[static_cast<std::size_t>(v)];
        key[static_cast<std::size_t>(v)] =
            ((std::int64_t{l[2]} * ly + l[1]) * 2 + (l[0] & 1)) * lx + l[0];
    }
    vertex_of.resize(static_cast<std::size_t>(nv));
    std::iota(vertex_of.begin(), vertex_of.end(), 0);
    std::sort(vertex_of.begin(), vertex_of.end(), [&](std::int32_t a, std::int32_t b) {
        return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
    });
    solver_index.resize(static_cast<std::size_t>(nv));
    for (std::int64_t p = 0; p < nv; ++p) {
        solver_index[static_cast<std::size_t>(vertex_of[static_cast<std::size_t>(p)])] =
            static_cast<std::int32_t>(p);
    }
}

// Reorders the constraints (vertices, and every array of rest data parallel to them) within each
// colour and each group of equal keys into runs (LatticeRun), and lists the runs. keys: per
// constraint in colour order, grouped within each colour (sorted when the layout is blocked).
template <std::size_t K>
void reorder_into_runs(const ConstraintColoring& coloring, const std::vector<std::int32_t>& keys,
                       std::vector<std::array<std::int32_t, K>>& vertices,
                       std::span<std::vector<float>* const> rest,
                       const std::vector<std::int32_t>& solver_index, std::vector<LatticeRun>& runs,
                       std::vector<std::int64_t>& run_begins,
                       std::vector<std::int64_t>& run_offsets) {
    using Constraint = std::array<std::int32_t, K>;
    const auto solver = [&](std::int64_t q) {
        Constraint p{};
        for (std::size_t m = 0; m < K; ++m) {
            p[m] = solver_index[static_cast<std::size_t>(vertices[static_cast<std::size_t>(q)][m])];
        }
        return p;
    };
    // Sort key: the offsets of the other vertices from the first, then the first.
    const auto shape = [](const Constraint& p) {
        Constraint s{};
        for (std::size_t m = 1; m < K; ++m) {
            s[m - 1] = p[m] - p[0];
        }
        s[K - 1] = p[0];
        return s;
    };
    std::vector<std::int64_t> order;
    std::vector<Constraint> sorted;
    std::vector<float> sorted_rest;
    run_offsets.assign(1, 0);
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        const std::int64_t end = coloring.offsets[static_cast<std::size_t>(c) + 1];
        order.clear();
        for (std::int64_t g = begin; g < end;) {
            std::int64_t g_end = g + 1;
            while (g_end < end &&
                   keys[static_cast<std::size_t>(g_end)] == keys[static_cast<std::size_t>(g)]) {
                ++g_end;
            }
            const auto first = static_cast<std::ptrdiff_t>(order.size());
            for (std::int64_t q = g; q < g_end; ++q) {
                order.push_back(q);
            }
            std::sort(order.begin() + first, order.end(), [&](std::int64_t a, std::int64_t b) {
                return shape(solver(a)) < shape(solver(b));
            });
            // Runs: each vertex one further than in the previous constraint.
            for (auto i = static_cast<std::size_t>(first); i < order.size(); ++i) {
                const Constraint p = solver(order[i]);
                bool continues = i > static_cast<std::size_t>(first);
                if (continues) {
                    const Constraint previous = solver(order[i - 1]);
                    for (std::size_t m = 0; m < K; ++m) {
                        continues = continues && p[m] == previous[m] + 1;
                    }
                }
                if (!continues) {
                    LatticeRun run{begin + static_cast<std::int64_t>(i), {}};
                    std::copy(p.begin(), p.end(), run.first.begin());
                    runs.push_back(run);
                    run_begins.push_back(run.begin);
                }
            }
            g = g_end;
        }
        run_offsets.push_back(static_cast<std::int64_t>(runs.size()));
        // Permute the colour's constraints and rest data into `order`.
        sorted.clear();
        for (const std::int64_t q : order) {
            sorted.push_back(vertices[static_cast<std::size_t>(q)]);
        }
        std::copy(sorted.begin(), sorted.end(), vertices.begin() + begin);
        for (std::vector<float>* data : rest) {
            sorted_rest.clear();
            for (const std::int64_t q : order) {
                sorted_rest.push_back((*data)[static_cast<std::size_t>(q)]);
            }
            std::copy(sorted_rest.begin(), sorted_rest.end(), data->begin() + begin);
        }
    }
}

// The layer key of each constraint (its lowest lattice z; a tet's is its cell's).
template <std::size_t K>
std::vector<std::int32_t> layer_keys(const TetGrid& grid,
                                     const std::vector<std::array<std::int32_t, K>>& vertices) {
    std::vector<std::int32_t> keys;
    keys.reserve(vertices.size());
    for (const auto& constraint : vertices) {
        std::int32_t z = grid.vertex_lattice[static_cast<std::size_t>(constraint[0])][2];
        for (std::size_t m = 1; m < K; ++m) {
            z = std::min(z, grid.vertex_lattice[static_cast<std::size_t>(constraint[m])][2]);
        }
        keys.push_back(z);
    }
    return keys;
}

}  // namespace

LatticeSweep build_lattice_sweep(const TetGrid& grid, EdgeConstraints& edges,
                                 TetConstraints& tets) {
    LatticeSweep out;
    std::vector<std::int32_t> solver_index;
    solver_order(grid, out.vertex_of, solver_index);
    std::vector<float>* edge_rest[] = {&edges.rest_lengths0, &edges.rest_lengths};
    reorder_into_runs<2>(edges.coloring, layer_keys(grid, edges.vertices), edges.vertices,
                         edge_rest, solver_index, out.edge_runs, out.edge_run_begins,
                         out.edge_run_offsets);
    std::vector<float>* tet_rest[] = {&tets.rest_volumes0, &tets.rest_volumes};
    reorder_into_runs<4>(tets.coloring, layer_keys(grid, tets.vertices), tets.vertices, tet_rest,
                         solver_index, out.tet_runs, out.tet_run_begins, out.tet_run_offsets);
    const std::size_t nv = out.vertex_of.size();
    out.x.resize(nv);
    out.y.resize(nv);
    out.z.resize(nv);
    out.w.resize(nv);
    return out;
}

void project_lattice(Float4* x, LatticeSweep& sweep, const EdgeConstraints& edges,
                     const TetConstraints& tets, ConstraintStiffness edge_stiffness,
                     ConstraintStiffness tet_stiffness, std::span<std::uint8_t> tet_at_risk,
                     std::span<std::uint8_t> colour_at_risk) {
    const auto nv = static_cast<std::int64_t>(sweep.vertex_of.size());
    const SoaPositions p{sweep.x.data(), sweep.y.data(), sweep.z.data(), sweep.w.data()};
    const std::int32_t* vertex_of = sweep.vertex_of.data();
    parallel_for(
        nv,
        [&](std::int64_t i) {
            const Float4& v = x[vertex_of[i]];
            p.x[i] = v.x;
            p.y[i] = v.y;
            p.z[i] = v.z;
            p.w[i] = v.w;
        },
        VERTEX_GRAIN);

    // The runs of colour c.
    const auto colour_runs = [](const ConstraintColoring& coloring,
                                const std::vector<LatticeRun>& runs,
                                const std::vector<std::int64_t>& run_begins,
                                const std::vector<std::int64_t>& run_offsets, std::int32_t c) {
        const auto colour = static_cast<std::size_t>(c);
        const std::int64_t r0 = run_offsets[colour];
        return LatticeRuns{runs.data() + r0, run_begins.data() + r0, run_offsets[colour + 1] - r0,
                           coloring.offsets[colour],
                           coloring.offsets[colour + 1] - coloring.offsets[colour]};
    };

    // Step 2: edges.
    sweep_colours(
        edges.blocking, edges.coloring, [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
            const LatticeRuns runs = colour_runs(edges.coloring, sweep.edge_runs,
                                                 sweep.edge_run_begins, sweep.edge_run_offsets, c);
            const float* lengths = edges.rest_lengths.data() + runs.begin;
            parallel_for_chunks(
                hi - lo, LATTICE_EDGE_GRAIN, [&](std::int64_t, std::int64_t b, std::int64_t e) {
                    project_edge_runs_soa_avx2(p, runs, lo + b, lo + e, lengths,
                                               edge_stiffness.inv_k, edge_stiffness.alpha);
                });
        });

    // Step 3: tets, flagging those at risk.
    sweep_colours(
        tets.blocking, tets.coloring, [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
            const LatticeRuns runs = colour_runs(tets.coloring, sweep.tet_runs,
                                                 sweep.tet_run_begins, sweep.tet_run_offsets, c);
            const float* volumes = tets.rest_volumes.data() + runs.begin;
            std::uint8_t* at_risk = tet_at_risk.data() + runs.begin;
            parallel_for_chunks(
                hi - lo, LATTICE_TET_GRAIN, [&](std::int64_t, std::int64_t b, std::int64_t e) {
                    std::int64_t num_at_risk = 0;
                    project_tet_runs_soa_avx2(p, runs, lo + b, lo + e, volumes, at_risk,
                                              tet_stiffness.inv_k, tet_stiffness.alpha,
                                              num_at_risk);
                    if (num_at_risk > 0) {
                        // Chunks of one colour may set it concurrently: idempotent.
                        std::atomic_ref<std::uint8_t>(colour_at_risk[static_cast<std::size_t>(c)])
                            .store(1, std::memory_order_relaxed);
                    }
                });
        });

    parallel_for(
        nv,
        [&](std::int64_t i) {
            Float4& v = x[vertex_of[i]];
            v.x = p.x[i];
            v.y = p.y[i];
            v.z = p.z[i];
        },
        VERTEX_GRAIN);
}

}  // namespace pliant::pbd::detail
