#include "pliant/pbd/detail/constraint_sweep.hpp"

#include <atomic>

#include "pliant/core/parallel.hpp"
#include "pliant/pbd/detail/grains.hpp"
#include "pliant/pbd/detail/projection_avx2.hpp"

namespace pliant::pbd::detail {
namespace {

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
    sweep_colours(edges.blocking, edges.coloring,
                  [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
                      project_edge_chunks(x, edges, c, lo, hi, stiffness, use_avx2);
                  });
}

void project_tets(Float4* x, const TetConstraints& tets, ConstraintStiffness stiffness,
                  bool use_avx2, std::span<std::uint8_t> tet_at_risk,
                  std::span<std::uint8_t> colour_at_risk) {
    sweep_colours(tets.blocking, tets.coloring,
                  [&](std::int32_t c, std::int64_t lo, std::int64_t hi) {
                      const auto colour = static_cast<std::size_t>(c);
                      std::uint8_t* at_risk = tet_at_risk.data() + tets.coloring.offsets[colour];
                      project_tet_chunks(x, tets, c, lo, hi, stiffness, use_avx2, at_risk,
                                         colour_at_risk[colour]);
                  });
}

}  // namespace pliant::pbd::detail
