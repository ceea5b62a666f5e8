// AVX2 kernel of volume::InverseMap::build's pass over the tets, compiled for AVX2 with a function
// attribute and chosen at run time (pliant::has_avx2(), core/simd_dispatch.hpp): the node box of 8
// tets and the test of each box's first node, 4 tets per vector, each lane the IEEE operations of
// the scalar pass (inverse_map.cpp: node_range(), detail::TetMap::lambda()) in the same order,
// without FMA contraction, so that the map is bit for bit the scalar pass's.
#pragma once

#include <cstdint>

namespace pliant::volume::detail {

constexpr int TET_BATCH = 8;

// What box_first_avx2() finds for 8 tets.
struct BoxFirst {
    std::int32_t lo[3][TET_BATCH];  // the node box per axis, where bit i of `boxes` is set
    std::int32_t hi[3][TET_BATCH];
    double l[3][TET_BATCH];  // λ0..2 of the box's first node (lo) where bit i of `inside` is set
    int boxes = 0;           // bit i: tet i is not degenerate and its box holds a node
    int inside = 0;          // bit i: and the box's first node lies in it (λ ≥ −1e-9)
};

// Tets i < 8 with deformed vertices p[vertex][axis][i] (target grid coordinates, finite), frame
// rows[k][axis][i] and determinant det[i] (inverse_map.cpp's FrameBatch): a tet is degenerate
// when det is 0 or not finite; its node box along axis a is [max(0, ceil(min_v p / B)),
// min(nodes[a] − 1, floor(max_v p / B))] (x · inv_b for x / B when inv_b > 0: B a power of two);
// its first node (lo) at B · lo is inside when the smallest of λ0..2 = rows[k] · (x − p3) and
// λ3 = 1 − λ0 − λ1 − λ2, taken as std::min({λ0, λ1, λ2, λ3}) takes it, is ≥ −1e-9. Returns false
// (out unset) without AVX2 on this target.
bool box_first_avx2(const double p[4][3][TET_BATCH], const double rows[3][3][TET_BATCH],
                    const double det[TET_BATCH], double b, double inv_b,
                    const std::int64_t nodes[3], BoxFirst& out);

}  // namespace pliant::volume::detail
