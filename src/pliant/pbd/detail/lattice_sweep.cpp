#include "pliant/pbd/detail/lattice_sweep.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <numeric>
#include <thread>
#include <utility>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"
#include "pliant/pbd/detail/integration_avx2.hpp"
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
                       std::vector<std::int8_t>& lanes,
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
                const std::int8_t lane_a = lanes[static_cast<std::size_t>(a)];
                const std::int8_t lane_b = lanes[static_cast<std::size_t>(b)];
                return lane_a != lane_b ? lane_a < lane_b : shape(solver(a)) < shape(solver(b));
            });
            // Runs: each vertex one further than in the previous constraint.
            for (auto i = static_cast<std::size_t>(first); i < order.size(); ++i) {
                const Constraint p = solver(order[i]);
                bool continues = i > static_cast<std::size_t>(first) &&
                                 lanes[static_cast<std::size_t>(order[i])] ==
                                     lanes[static_cast<std::size_t>(order[i - 1])];
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
        std::vector<std::int8_t> sorted_lanes;
        sorted_lanes.reserve(order.size());
        for (const std::int64_t q : order) {
            sorted_lanes.push_back(lanes[static_cast<std::size_t>(q)]);
        }
        std::copy(sorted_lanes.begin(), sorted_lanes.end(), lanes.begin() + begin);
        for (std::vector<float>* data : rest) {
            sorted_rest.clear();
            for (const std::int64_t q : order) {
                sorted_rest.push_back((*data)[static_cast<std::size_t>(q)]);
            }
            std::copy(sorted_rest.begin(), sorted_rest.end(), data->begin() + begin);
        }
    }
}

// The lowest lattice coordinate `axis` of each constraint's vertices: its layer key (z; a tet's
// is its cell's) or its row key (y).
template <std::size_t K>
std::vector<std::int32_t> lowest_lattice(const TetGrid& grid,
                                         const std::vector<std::array<std::int32_t, K>>& vertices,
                                         int axis) {
    const auto a = static_cast<std::size_t>(axis);
    std::vector<std::int32_t> keys;
    keys.reserve(vertices.size());
    for (const auto& constraint : vertices) {
        std::int32_t key = grid.vertex_lattice[static_cast<std::size_t>(constraint[0])][a];
        for (std::size_t m = 1; m < K; ++m) {
            key = std::min(key, grid.vertex_lattice[static_cast<std::size_t>(constraint[m])][a]);
        }
        keys.push_back(key);
    }
    return keys;
}

// The lane of each constraint (colour order): with y its row key plus its colour's skew, the
// number of boundaries ≤ y, the boundaries splitting the constraints' y into SWEEP_LANES parts of
// about equal counts; all 0 when skews is empty.
std::vector<std::int8_t> constraint_lanes(const ConstraintColoring& coloring,
                                          const std::vector<std::int32_t>& row,
                                          const std::vector<std::int64_t>& skews) {
    std::vector<std::int8_t> lanes(row.size(), 0);
    if (skews.empty() || row.empty()) {
        return lanes;
    }
    std::vector<std::int64_t> skewed(row.size());
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        for (std::int64_t q = coloring.offsets[static_cast<std::size_t>(c)];
             q < coloring.offsets[static_cast<std::size_t>(c) + 1]; ++q) {
            skewed[static_cast<std::size_t>(q)] =
                row[static_cast<std::size_t>(q)] + skews[static_cast<std::size_t>(c)];
        }
    }
    std::vector<std::int64_t> sorted = skewed;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::int64_t> boundaries;
    for (std::int64_t b = 1; b < SWEEP_LANES; ++b) {
        boundaries.push_back(
            sorted[static_cast<std::size_t>(b * std::ssize(sorted) / SWEEP_LANES)]);
    }
    for (std::size_t q = 0; q < row.size(); ++q) {
        std::int8_t lane = 0;
        for (const std::int64_t b : boundaries) {
            lane = static_cast<std::int8_t>(lane + (skewed[q] >= b ? 1 : 0));
        }
        lanes[q] = lane;
    }
    return lanes;
}

// lane_begin (LatticeSweep) from the layer keys and lanes of the reordered constraints.
std::vector<std::int64_t> lane_begins(const ConstraintColoring& coloring,
                                      const LayerBlocking& blocking,
                                      const std::vector<std::int32_t>& keys,
                                      const std::vector<std::int8_t>& lanes) {
    const std::int64_t per_colour = blocking.num_layers * SWEEP_LANES + 1;
    std::vector<std::int64_t> out(static_cast<std::size_t>(coloring.num_colors() * per_colour));
    for (std::int32_t c = 0; c < coloring.num_colors(); ++c) {
        const std::int64_t begin = coloring.offsets[static_cast<std::size_t>(c)];
        const std::int64_t end = coloring.offsets[static_cast<std::size_t>(c) + 1];
        std::int64_t* entry = out.data() + static_cast<std::size_t>(c * per_colour);
        std::int64_t q = begin;
        for (std::int64_t slot = 0; slot < per_colour; ++slot) {
            // The first constraint with (key, lane) ≥ (slot / SWEEP_LANES, slot % SWEEP_LANES).
            while (q < end && std::int64_t{keys[static_cast<std::size_t>(q)]} * SWEEP_LANES +
                                      lanes[static_cast<std::size_t>(q)] <
                                  slot) {
                ++q;
            }
            entry[slot] = q - begin;
        }
    }
    return out;
}

// Steps 2 or 3 through the lanes (LatticeSweep): project_range(c, lo, hi) for the constraints
// [lo, hi) of colour c, every (slab, lane) item's colours in order; items claimed in the order of
// their diagonals slab + lane, each after items (slab − 1, lane) and (slab, lane − 1) are done.
// Every item an item depends on was claimed before it by a running worker, so the waits end with
// any number of workers (one worker: the items in claim order).
template <typename ProjectRange>
void sweep_lanes(const LayerBlocking& blocking, std::int32_t num_colors,
                 const std::vector<std::int64_t>& lane_begin, const ProjectRange& project_range) {
    const std::int64_t layers = blocking.num_layers;
    const std::int64_t num_slabs =
        (layers + blocking.max_skew + LAYERS_PER_SLAB - 1) / LAYERS_PER_SLAB;
    const std::int64_t per_colour = layers * SWEEP_LANES + 1;
    std::vector<std::array<std::int64_t, 2>> items;  // (slab, lane)
    for (std::int64_t d = 0; d < num_slabs + SWEEP_LANES - 1; ++d) {
        for (std::int64_t lane = 0; lane < SWEEP_LANES; ++lane) {
            if (d - lane >= 0 && d - lane < num_slabs) {
                items.push_back({d - lane, lane});
            }
        }
    }
    std::array<std::atomic<std::int64_t>, SWEEP_LANES> done{};  // slabs done, per lane
    std::atomic<std::int64_t> next{0};
    const auto wait_for = [](const std::atomic<std::int64_t>& counter, std::int64_t target) {
        for (int spins = 0; counter.load(std::memory_order_acquire) < target; ++spins) {
            if (spins >= 64) {
                std::this_thread::yield();
            }
        }
    };
    const std::int64_t workers = std::min<std::int64_t>(num_threads(), SWEEP_LANES);
    parallel_for_chunks(workers, 1, [&](std::int64_t, std::int64_t, std::int64_t) {
        for (std::int64_t i = next.fetch_add(1, std::memory_order_relaxed); i < std::ssize(items);
             i = next.fetch_add(1, std::memory_order_relaxed)) {
            const auto [slab, lane] = items[static_cast<std::size_t>(i)];
            wait_for(done[static_cast<std::size_t>(lane)], slab);
            if (lane > 0) {
                wait_for(done[static_cast<std::size_t>(lane - 1)], slab + 1);
            }
            const std::int64_t t = slab * LAYERS_PER_SLAB;
            for (std::int32_t c = 0; c < num_colors; ++c) {
                const std::int64_t skew = blocking.skew[static_cast<std::size_t>(c)];
                const std::int64_t z0 = std::clamp<std::int64_t>(t - skew, 0, layers);
                const std::int64_t z1 =
                    std::clamp<std::int64_t>(t - skew + LAYERS_PER_SLAB, 0, layers);
                const std::int64_t* begin =
                    lane_begin.data() + static_cast<std::size_t>(c) * per_colour;
                for (std::int64_t z = z0; z < z1; ++z) {
                    const std::int64_t lo = begin[z * SWEEP_LANES + lane];
                    const std::int64_t hi = begin[z * SWEEP_LANES + lane + 1];
                    if (lo < hi) {
                        project_range(c, lo, hi);
                    }
                }
            }
            done[static_cast<std::size_t>(lane)].store(slab + 1, std::memory_order_release);
        }
    });
}

}  // namespace

LatticeSweep build_lattice_sweep(const TetGrid& grid, EdgeConstraints& edges,
                                 TetConstraints& tets) {
    LatticeSweep out;
    std::vector<std::int32_t>& solver_index = out.solver_index;
    solver_order(grid, out.vertex_of, solver_index);
    // Lanes (LatticeSweep): rows, per colour skewed, split at the median.
    const std::vector<std::int32_t> edge_rows = lowest_lattice(grid, edges.vertices, 1);
    const std::vector<std::int32_t> tet_rows = lowest_lattice(grid, tets.vertices, 1);
    const std::vector<std::int32_t> vertex_rows = vertex_lattice_axis(grid, 1);
    const std::vector<std::int64_t> edge_skews =
        colour_skews(edges.coloring, edges.vertices, edge_rows, vertex_rows);
    const std::vector<std::int64_t> tet_skews =
        colour_skews(tets.coloring, tets.vertices, tet_rows, vertex_rows);
    std::vector<std::int8_t> edge_lanes = constraint_lanes(edges.coloring, edge_rows, edge_skews);
    std::vector<std::int8_t> tet_lanes = constraint_lanes(tets.coloring, tet_rows, tet_skews);

    const std::vector<std::int32_t> edge_keys = lowest_lattice(grid, edges.vertices, 2);
    std::vector<float>* edge_rest[] = {&edges.rest_lengths0, &edges.rest_lengths};
    reorder_into_runs<2>(edges.coloring, edge_keys, edge_lanes, edges.vertices, edge_rest,
                         solver_index, out.edge_runs, out.edge_run_begins, out.edge_run_offsets);
    const std::vector<std::int32_t> tet_keys = lowest_lattice(grid, tets.vertices, 2);
    std::vector<float>* tet_rest[] = {&tets.rest_volumes0, &tets.rest_volumes};
    reorder_into_runs<4>(tets.coloring, tet_keys, tet_lanes, tets.vertices, tet_rest, solver_index,
                         out.tet_runs, out.tet_run_begins, out.tet_run_offsets);
    if (!edge_skews.empty() && !tet_skews.empty() && edges.blocking.num_layers > 0 &&
        tets.blocking.num_layers > 0) {
        out.edge_lane_begin = lane_begins(edges.coloring, edges.blocking, edge_keys, edge_lanes);
        out.tet_lane_begin = lane_begins(tets.coloring, tets.blocking, tet_keys, tet_lanes);
    }
    const std::size_t nv = out.vertex_of.size();
    out.x.resize(nv);
    out.y.resize(nv);
    out.z.resize(nv);
    out.w.resize(nv);
    return out;
}

namespace {
SoaPositions positions_of(LatticeSweep& sweep) {
    return {sweep.x.data(), sweep.y.data(), sweep.z.data(), sweep.w.data()};
}

// x's positions and inverse masses into the arrays.
void load_positions(const Float4* x, LatticeSweep& sweep) {
    const auto nv = static_cast<std::int64_t>(sweep.vertex_of.size());
    const SoaPositions p = positions_of(sweep);
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
}

}  // namespace

void load_lattice(const Float4* x, std::span<const Vec3f> previous,
                  std::span<const float> inv_masses, std::span<const std::uint8_t> pinned,
                  LatticeSweep& sweep) {
    const auto nv = static_cast<std::int64_t>(sweep.vertex_of.size());
    sweep.previous_x.resize(static_cast<std::size_t>(nv));
    sweep.previous_y.resize(static_cast<std::size_t>(nv));
    sweep.previous_z.resize(static_cast<std::size_t>(nv));
    sweep.inv_masses.resize(static_cast<std::size_t>(nv));
    sweep.pinned.resize(static_cast<std::size_t>(nv));
    load_positions(x, sweep);
    const std::int32_t* vertex_of = sweep.vertex_of.data();
    parallel_for(
        nv,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(vertex_of[i]);
            const auto k = static_cast<std::size_t>(i);
            sweep.previous_x[k] = previous[v].x;
            sweep.previous_y[k] = previous[v].y;
            sweep.previous_z[k] = previous[v].z;
            sweep.inv_masses[k] = inv_masses[v];
            sweep.pinned[k] = pinned[v];
        },
        VERTEX_GRAIN);
}

void load_lattice_vertices(const Float4* x, std::span<const std::int32_t> vertices,
                           LatticeSweep& sweep) {
    const SoaPositions p = positions_of(sweep);
    for (const std::int32_t v : vertices) {
        const Float4& q = x[v];
        const auto i = static_cast<std::size_t>(sweep.solver_index[static_cast<std::size_t>(v)]);
        p.x[i] = q.x;
        p.y[i] = q.y;
        p.z[i] = q.z;
        p.w[i] = q.w;
    }
}

void guard_lattice(LatticeSweep& sweep, const TetConstraints& tets, InversionFlags& flags) {
    guard_flagged_tets(positions_of(sweep), sweep.solver_index.data(), tets, flags);
}

void finish_lattice_substep(LatticeSweep& sweep, const SubstepMotion& m) {
    const auto nv = static_cast<std::int64_t>(sweep.vertex_of.size());
    const SoaMotion arrays{positions_of(sweep),     sweep.previous_x.data(),
                           sweep.previous_y.data(), sweep.previous_z.data(),
                           sweep.inv_masses.data(), sweep.pinned.data()};
    // update_velocities_and_predict's substep_velocity and predict_vertex, 8 vertices at a time
    // (the same bits).
    parallel_for_chunks(nv, VERTEX_GRAIN, [&](std::int64_t, std::int64_t begin, std::int64_t end) {
        finish_substep_soa_avx2(arrays, begin, end, m);
    });
}

void finish_lattice_step(const LatticeSweep& sweep, const SubstepMotion& m, Float4* x,
                         std::span<Vec3f> previous, std::span<Vec3f> velocities,
                         std::span<Vec3f> positions) {
    const auto nv = static_cast<std::int64_t>(sweep.vertex_of.size());
    const std::int32_t* vertex_of = sweep.vertex_of.data();
    parallel_for(
        nv,
        [&](std::int64_t i) {
            const auto v = static_cast<std::size_t>(vertex_of[i]);
            const auto k = static_cast<std::size_t>(i);
            const Float4 q{sweep.x[k], sweep.y[k], sweep.z[k], sweep.w[k]};
            const Vec3f before{sweep.previous_x[k], sweep.previous_y[k], sweep.previous_z[k]};
            x[v] = q;
            previous[v] = before;
            if (sweep.pinned[k] == 0) {
                velocities[v] = substep_velocity(q, before, m);
            }
            positions[v] = {q.x, q.y, q.z};
        },
        VERTEX_GRAIN);
}

void project_lattice(Float4* x, LatticeSweep& sweep, const EdgeConstraints& edges,
                     const TetConstraints& tets, ConstraintStiffness edge_stiffness,
                     ConstraintStiffness tet_stiffness, std::span<std::uint8_t> tet_at_risk,
                     std::span<std::uint8_t> colour_at_risk) {
    load_positions(x, sweep);
    sweep_lattice(sweep, edges, tets, edge_stiffness, tet_stiffness, tet_at_risk, colour_at_risk);
    const auto nv = static_cast<std::int64_t>(sweep.vertex_of.size());
    const SoaPositions p = positions_of(sweep);
    const std::int32_t* vertex_of = sweep.vertex_of.data();
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

void sweep_lattice(LatticeSweep& sweep, const EdgeConstraints& edges, const TetConstraints& tets,
                   ConstraintStiffness edge_stiffness, ConstraintStiffness tet_stiffness,
                   std::span<std::uint8_t> tet_at_risk, std::span<std::uint8_t> colour_at_risk) {
    const SoaPositions p = positions_of(sweep);

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

    if (!sweep.edge_lane_begin.empty() && num_threads() > 1) {
        // Steps 2 and 3 through the lanes, flagging the tets at risk (on one thread the chunks
        // below are as fast or faster: fewer, longer kernel calls).
        sweep_lanes(edges.blocking, edges.coloring.num_colors(), sweep.edge_lane_begin,
                    [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
                        const LatticeRuns runs =
                            colour_runs(edges.coloring, sweep.edge_runs, sweep.edge_run_begins,
                                        sweep.edge_run_offsets, c);
                        project_edge_runs_soa_avx2(p, runs, lo, hi,
                                                   edges.rest_lengths.data() + runs.begin,
                                                   edge_stiffness.inv_k, edge_stiffness.alpha);
                    });
        sweep_lanes(
            tets.blocking, tets.coloring.num_colors(), sweep.tet_lane_begin,
            [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
                const LatticeRuns runs = colour_runs(
                    tets.coloring, sweep.tet_runs, sweep.tet_run_begins, sweep.tet_run_offsets, c);
                std::int64_t num_at_risk = 0;
                project_tet_runs_soa_avx2(p, runs, lo, hi, tets.rest_volumes.data() + runs.begin,
                                          tet_at_risk.data() + runs.begin, tet_stiffness.inv_k,
                                          tet_stiffness.alpha, num_at_risk);
                if (num_at_risk > 0) {
                    // Both lanes may set it concurrently: idempotent.
                    std::atomic_ref<std::uint8_t>(colour_at_risk[static_cast<std::size_t>(c)])
                        .store(1, std::memory_order_relaxed);
                }
            });
    } else {
        // Step 2: edges.
        sweep_colours(
            edges.blocking, edges.coloring, [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
                const LatticeRuns runs =
                    colour_runs(edges.coloring, sweep.edge_runs, sweep.edge_run_begins,
                                sweep.edge_run_offsets, c);
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
                const LatticeRuns runs = colour_runs(
                    tets.coloring, sweep.tet_runs, sweep.tet_run_begins, sweep.tet_run_offsets, c);
                const float* volumes = tets.rest_volumes.data() + runs.begin;
                std::uint8_t* at_risk = tet_at_risk.data() + runs.begin;
                parallel_for_chunks(hi - lo, LATTICE_TET_GRAIN,
                                    [&](std::int64_t, std::int64_t b, std::int64_t e) {
                                        std::int64_t num_at_risk = 0;
                                        project_tet_runs_soa_avx2(p, runs, lo + b, lo + e, volumes,
                                                                  at_risk, tet_stiffness.inv_k,
                                                                  tet_stiffness.alpha, num_at_risk);
                                        if (num_at_risk > 0) {
                                            // Chunks of one colour may set it concurrently:
                                            // idempotent.
                                            std::atomic_ref<std::uint8_t>(
                                                colour_at_risk[static_cast<std::size_t>(c)])
                                                .store(1, std::memory_order_relaxed);
                                        }
                                    });
            });
    }
}

}  // namespace pliant::pbd::detail
