#include "pliant/pbd/detail/constraint_sweep.hpp"

#include <atomic>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"

namespace pliant::pbd::detail {
namespace {

// Edges [lo, hi) of colour c (indices within the colour) on a TetGrid with AVX2, in fixed chunks
// of the range: within a run the edges' vertices follow from the run's first vertex; the run's
// last count mod 8 edges take the scalar kernel.
void project_edge_runs(Float4* x, const EdgeConstraints& constraints, std::int32_t c,
                       std::int64_t lo, std::int64_t hi, ConstraintStiffness k) {
    const auto colour = static_cast<std::size_t>(c);
    const std::int64_t begin = constraints.coloring.offsets[colour];
    const std::int64_t count = constraints.coloring.offsets[colour + 1] - begin;
    const auto* edges = constraints.vertices.data() + begin;
    const float* lengths = constraints.rest_lengths.data() + begin;
    const std::int64_t* run_begins =
        constraints.run_begins.data() + constraints.run_offsets[colour];
    const std::int64_t num_runs =
        constraints.run_offsets[colour + 1] - constraints.run_offsets[colour];
    const EdgeRun* runs = constraints.runs.data() + constraints.run_offsets[colour];
    parallel_for_chunks(hi - lo, EDGE_GRAIN, [&](std::int64_t, std::int64_t b, std::int64_t e) {
        b += lo;
        e += lo;
        // The run holding edge b (its begin is the last ≤ begin + b).
        std::int64_t r =
            std::upper_bound(run_begins, run_begins + num_runs, begin + b) - run_begins - 1;
        for (std::int64_t q = b; q < e; ++r) {
            const EdgeRun& run = runs[r];
            const std::int64_t run_end = r + 1 < num_runs ? run_begins[r + 1] - begin : count;
            const std::int64_t n_run = std::min(e, run_end) - q;
            std::int64_t i = q + project_edge_run_avx2(
                                     x, run.first + run.stride * (begin + q - run.begin),
                                     run.stride, run.span, lengths + q, n_run, k.inv_k, k.alpha);
            for (; i < q + n_run; ++i) {
                project_edge(x, edges[i][0], edges[i][1], lengths[i], k.inv_k, k.alpha);
            }
            q += n_run;
        }
    });
}

// Edges [lo, hi) of colour c, any mesh, in fixed chunks of the range: 8 at a time (use_avx2), then
// 4 (SSE), then 1.
void project_edge_chunks(Float4* x, const EdgeConstraints& constraints, std::int32_t c,
                         std::int64_t lo, std::int64_t hi, ConstraintStiffness k, bool use_avx2) {
    const std::int64_t begin = constraints.coloring.offsets[static_cast<std::size_t>(c)];
    const auto* edges = constraints.vertices.data() + begin;
    const float* lengths = constraints.rest_lengths.data() + begin;
    parallel_for_chunks(hi - lo, EDGE_GRAIN, [&](std::int64_t, std::int64_t b, std::int64_t e) {
        std::int64_t i = lo + b;
        e += lo;
        if (use_avx2) {
            i += project_edges_avx2(x, edges + i, lengths + i, e - i, k.inv_k, k.alpha);
        }
#if defined(PLIANT_PBD_SSE)
        for (; i + 4 <= e; i += 4) {
            project_edges4(x, edges + i, lengths + i, k.inv_k, k.alpha);
        }
#endif
        for (; i < e; ++i) {
            project_edge(x, edges[i][0], edges[i][1], lengths[i], k.inv_k, k.alpha);
        }
    });
}

// The scalar projection of one tet, flagging it (at_risk = 1, ++num_at_risk) when at risk.
void project_tet_flagging(Float4* x, const geometry::Tet& tet, float rest_volume,
                          ConstraintStiffness k, std::uint8_t& at_risk, std::int64_t& num_at_risk) {
    if (project_tet(x, tet, rest_volume, k.inv_k, k.alpha)) {
        at_risk = 1;
        ++num_at_risk;
    }
}

// Sets colour_at_risk (a colour's flag) when a chunk flagged tets: a relaxed atomic store, as
// chunks of one colour may set it concurrently.
void flag_colour(std::uint8_t& colour_at_risk, std::int64_t num_at_risk) {
    if (num_at_risk > 0) {
        std::atomic_ref<std::uint8_t>(colour_at_risk).store(1, std::memory_order_relaxed);
    }
}

// Tets [lo, hi) of colour c on a full-box TetGrid with AVX2, in fixed chunks of the range: rows
// of cells along x, within a row the tets' vertices follow from the cell base (TetRun); a row's
// last count mod 8 tets take the scalar kernel. at_risk: the colour's entries of tet_at_risk.
void project_tet_runs(Float4* x, const TetConstraints& constraints, std::int32_t c, std::int64_t lo,
                      std::int64_t hi, ConstraintStiffness k, std::uint8_t* at_risk,
                      std::uint8_t& colour_at_risk) {
    const std::int64_t begin = constraints.coloring.offsets[static_cast<std::size_t>(c)];
    const geometry::Tet* tets = constraints.vertices.data() + begin;
    const float* volumes = constraints.rest_volumes.data() + begin;
    const TetRun& r = constraints.runs[static_cast<std::size_t>(c)];
    parallel_for_chunks(hi - lo, TET_GRAIN, [&](std::int64_t, std::int64_t b, std::int64_t e) {
        b += lo;
        e += lo;
        std::int64_t num_at_risk = 0;
        for (std::int64_t q = b; q < e;) {
            const std::int64_t row = q / r.ni;
            const std::int64_t a = q - row * r.ni;
            const std::int64_t base = r.i0 + 2 * a +
                                      constraints.lattice_x * (r.j0 + 2 * (row % r.nj)) +
                                      constraints.lattice_xy * (r.k0 + 2 * (row / r.nj));
            const std::int64_t run = std::min(e - q, r.ni - a);
            std::int64_t i = q + project_tet_run_avx2(x, base, r.offsets, volumes + q, at_risk + q,
                                                      run, k.inv_k, k.alpha, num_at_risk);
            for (; i < q + run; ++i) {
                project_tet_flagging(x, tets[i], volumes[i], k, at_risk[i], num_at_risk);
            }
            q += run;
        }
        flag_colour(colour_at_risk, num_at_risk);
    });
}

// Tets [lo, hi) of colour c, any mesh, in fixed chunks of the range: 8 at a time (use_avx2), then
// 4 (SSE), then 1.
void project_tet_chunks(Float4* x, const TetConstraints& constraints, std::int32_t c,
                        std::int64_t lo, std::int64_t hi, ConstraintStiffness k, bool use_avx2,
                        std::uint8_t* at_risk, std::uint8_t& colour_at_risk) {
    const std::int64_t begin = constraints.coloring.offsets[static_cast<std::size_t>(c)];
    const geometry::Tet* tets = constraints.vertices.data() + begin;
    const float* volumes = constraints.rest_volumes.data() + begin;
    parallel_for_chunks(hi - lo, TET_GRAIN, [&](std::int64_t, std::int64_t b, std::int64_t e) {
        std::int64_t i = lo + b;
        e += lo;
        std::int64_t num_at_risk = 0;
        if (use_avx2) {
            i += project_tets_avx2(x, tets + i, volumes + i, at_risk + i, e - i, k.inv_k, k.alpha,
                                   num_at_risk);
        }
#if defined(PLIANT_PBD_SSE)
        for (; i + 4 <= e; i += 4) {
            const int mask = project_tets4(x, tets + i, volumes + i, k.inv_k, k.alpha);
            for (int l = 0; mask != 0 && l < 4; ++l) {
                if ((mask >> l & 1) != 0) {
                    at_risk[i + l] = 1;
                    ++num_at_risk;
                }
            }
        }
#endif
        for (; i < e; ++i) {
            project_tet_flagging(x, tets[i], volumes[i], k, at_risk[i], num_at_risk);
        }
        flag_colour(colour_at_risk, num_at_risk);
    });
}

}  // namespace

void project_edges(Float4* x, const EdgeConstraints& edges, ConstraintStiffness stiffness,
                   bool use_avx2) {
    const bool use_runs = use_avx2 && !edges.runs.empty();
    sweep_colours(edges.blocking, edges.coloring,
                  [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
                      if (use_runs) {
                          project_edge_runs(x, edges, c, lo, hi, stiffness);
                      } else {
                          project_edge_chunks(x, edges, c, lo, hi, stiffness, use_avx2);
                      }
                  });
}

void project_tets(Float4* x, const TetConstraints& tets, ConstraintStiffness stiffness,
                  bool use_avx2, std::span<std::uint8_t> tet_at_risk,
                  std::span<std::uint8_t> colour_at_risk) {
    const bool use_runs = use_avx2 && !tets.runs.empty();
    sweep_colours(
        tets.blocking, tets.coloring, [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
            const auto colour = static_cast<std::size_t>(c);
            std::uint8_t* at_risk = tet_at_risk.data() + tets.coloring.offsets[colour];
            if (use_runs) {
                project_tet_runs(x, tets, c, lo, hi, stiffness, at_risk, colour_at_risk[colour]);
            } else {
                project_tet_chunks(x, tets, c, lo, hi, stiffness, use_avx2, at_risk,
                                   colour_at_risk[colour]);
            }
        });
}

}  // namespace pliant::pbd::detail
