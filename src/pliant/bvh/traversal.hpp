// Overlap queries on LBVHs: all pairs of primitives whose boxes overlap (closed intervals), and
// single queries — query_wide (leaves overlapping a box) and query_wide_nearest (closest-point
// queries: a box around a point that shrinks to the best distance found so far).
//
// Self: every unordered pair {a, b}, a ≠ b, of one tree, reported exactly once. Pair: every
// (a, b), a from tree A, b from tree B.
//
// Both use leaf clusters: the leaf slots of one wide node (up to four leaves, neighbours in Morton
// order) query a tree together with the union of their boxes; each leaf j found is then tested
// against the cluster's leaves in one SIMD step. This walks the upper tree once per cluster
// instead of once per leaf. For self queries, a cluster whose first leaf is at position f prunes
// every subtree whose leaves all come at or before f and pairs leaf i with found leaf j only when
// i < j — every pair once, by construction.
//
// Kernels are per cluster, GPU style (fixed-size stack, no allocation); the 4-wide nodes are
// tested with SSE where available (x86-64 always has SSE2), a scalar loop otherwise. Output goes
// through a visitor called as visit(chunk, a, b) with primitive ids. Clusters are processed in
// fixed chunks of CLUSTER_GRAIN nodes in node order, and within a cluster in traversal order, so
// a visitor that appends to per-chunk buffers (ChunkedBuffer sized by num_overlap_chunks) yields a
// result identical for 1 and N threads.
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::bvh {

// Deep enough for any LBVH: the wide tree has depth ≤ 63 (see lbvh.hpp) and every pop pushes at
// most WIDTH entries, so the stack never holds more than 3 · 63 + 1.
inline constexpr int TRAVERSAL_STACK = 192;
inline constexpr std::int64_t CLUSTER_GRAIN = 128;

// A query box prepared for repeated slot tests.
struct QueryBox {
#if defined(__SSE2__)
    __m128 lo_x, lo_y, lo_z, hi_x, hi_y, hi_z;
    explicit QueryBox(const AABB& b)
        : lo_x(_mm_set1_ps(b.lo.x)),
          lo_y(_mm_set1_ps(b.lo.y)),
          lo_z(_mm_set1_ps(b.lo.z)),
          hi_x(_mm_set1_ps(b.hi.x)),
          hi_y(_mm_set1_ps(b.hi.y)),
          hi_z(_mm_set1_ps(b.hi.z)) {}
#else
    AABB box;
    PLIANT_HOST_DEVICE explicit QueryBox(const AABB& b) : box(b) {}
#endif
};

// Bit k set when slot k's box overlaps the query (closed intervals) and last[k] > after.
// after = -1 keeps every used slot (unused slots have empty boxes and never pass).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE unsigned slot_mask(const WideNode& node, const QueryBox& q,
                                                          std::int32_t after) {
#if defined(__SSE2__)
    __m128 m = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(node.lo_x), q.hi_x),
                          _mm_cmple_ps(q.lo_x, _mm_load_ps(node.hi_x)));
    m = _mm_and_ps(m, _mm_cmple_ps(_mm_load_ps(node.lo_y), q.hi_y));
    m = _mm_and_ps(m, _mm_cmple_ps(q.lo_y, _mm_load_ps(node.hi_y)));
    m = _mm_and_ps(m, _mm_cmple_ps(_mm_load_ps(node.lo_z), q.hi_z));
    m = _mm_and_ps(m, _mm_cmple_ps(q.lo_z, _mm_load_ps(node.hi_z)));
    const __m128i later = _mm_cmpgt_epi32(
        _mm_load_si128(reinterpret_cast<const __m128i*>(node.last)), _mm_set1_epi32(after));
    return static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(m, _mm_castsi128_ps(later))));
#else
    unsigned mask = 0;
    for (int k = 0; k < WIDTH; ++k) {
        mask |= (node.last[k] > after && overlaps(node.box(k), q.box) ? 1u : 0u) << k;
    }
    return mask;
#endif
}

// Bit k set when slot k is a leaf whose box overlaps the query and whose position is < `before`
// (before = INT32_MAX: every leaf slot).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE unsigned leaf_slot_mask(const WideNode& node,
                                                               const QueryBox& q,
                                                               std::int32_t before) {
#if defined(__SSE2__)
    // Used leaf slots have child < 0 and last = their position; unused slots fail the box test.
    const __m128i leaf = _mm_cmplt_epi32(
        _mm_load_si128(reinterpret_cast<const __m128i*>(node.child)), _mm_setzero_si128());
    const __m128i earlier = _mm_cmplt_epi32(
        _mm_load_si128(reinterpret_cast<const __m128i*>(node.last)), _mm_set1_epi32(before));
    const auto mask =
        static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_and_si128(leaf, earlier))));
    return mask & slot_mask(node, q, -1);
#else
    unsigned mask = 0;
    for (int k = 0; k < WIDTH; ++k) {
        const bool used_leaf = node.child[k] < 0 && node.last[k] >= 0;  // not EMPTY_SLOT
        mask |= (used_leaf && node.last[k] < before && overlaps(node.box(k), q.box) ? 1u : 0u) << k;
    }
    return mask;
#endif
}

// Visits the tree from the root: on_leaf(j, box_j) for every leaf j > after whose box overlaps
// the query, pruning slots whose leaves all come at or before `after` (-1: no pruning). Leaves
// are reported in a fixed order that depends only on the tree and the query.
template <typename OnLeaf>
PLIANT_HOST_DEVICE void query_wide(const WideNode* nodes, const AABB& query, std::int32_t after,
                                   OnLeaf&& on_leaf) {
    const QueryBox q(query);
    std::int32_t stack[TRAVERSAL_STACK];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const WideNode& node = nodes[stack[--top]];
        unsigned mask = slot_mask(node, q, after);
        while (mask != 0) {
            const int k = std::countr_zero(mask);
            mask &= mask - 1;
            const std::int32_t c = node.child[k];
            if (is_leaf(c)) {
                on_leaf(leaf_position(c), node.box(k));
            } else {
                stack[top++] = c;
            }
        }
    }
}

// A float box containing [point - r, point + r] (r ≥ 0; r = +inf gives the whole space), for
// finite points. Each bound moves outward by 2^-22 of its magnitude plus 2^-126 before rounding to
// float, which covers the rounding (at most half a float ulp, 2^-24 relative) without the
// nextafter calls of outward_float: a few float ulps looser, branch free.
inline AABB query_box_around(const Vec3d& point, double radius) {
    const auto down = [](double v) {
        return static_cast<float>(v - std::abs(v) * 0x1p-22 - 0x1p-126);
    };
    const auto up = [](double v) {
        return static_cast<float>(v + std::abs(v) * 0x1p-22 + 0x1p-126);
    };
    return {{down(point.x - radius), down(point.y - radius), down(point.z - radius)},
            {up(point.x + radius), up(point.y + radius), up(point.z + radius)}};
}

// Squared distances from p to the four slot boxes (infinite for unused slots), in float: an
// ordering key, not a bound (p is rounded to float).
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE void slot_gaps(const WideNode& node, const Vec3f& p,
                                                      float gap2[WIDTH]) {
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps();
    const auto axis_gap = [&](const float* lo, const float* hi, float c) {
        const __m128 v = _mm_set1_ps(c);
        const __m128 g = _mm_max_ps(
            _mm_max_ps(_mm_sub_ps(_mm_load_ps(lo), v), _mm_sub_ps(v, _mm_load_ps(hi))), zero);
        return _mm_mul_ps(g, g);
    };
    _mm_storeu_ps(gap2, _mm_add_ps(_mm_add_ps(axis_gap(node.lo_x, node.hi_x, p.x),
                                              axis_gap(node.lo_y, node.hi_y, p.y)),
                                   axis_gap(node.lo_z, node.hi_z, p.z)));
#else
    for (int k = 0; k < WIDTH; ++k) {
        const float dx = std::max(std::max(node.lo_x[k] - p.x, p.x - node.hi_x[k]), 0.0f);
        const float dy = std::max(std::max(node.lo_y[k] - p.y, p.y - node.hi_y[k]), 0.0f);
        const float dz = std::max(std::max(node.lo_z[k] - p.z, p.z - node.hi_z[k]), 0.0f);
        gap2[k] = dx * dx + dy * dy + dz * dz;
    }
#endif
}

// Closest-point style query with a shrinking radius: visits the leaves whose boxes overlap the
// closed box [point - r, point + r], where r starts at `radius` (world units, ≥ 0; +inf visits
// every leaf; negative or NaN visits none) and becomes what on_leaf(j, box_j) returns — the
// caller's best distance so far — so later slots and subtrees are tested against a smaller box.
// A return value not below the current radius is ignored. The query box is rounded outward to
// float, so every leaf whose box is within r of `point` along each axis is visited: a caller
// returning the distance of its nearest primitive so far (a primitive is never farther than its
// box) meets every primitive at distance ≤ the final r, ties included. Slots are taken nearest
// box first (float distance from `point`, an ordering heuristic only), a node's leaves before its
// inner children, so r shrinks early. The visit order depends only on the tree, the query and
// on_leaf's return values. Precondition: the tree has nodes. Fixed-size stack, no allocation.
template <typename OnLeaf>
void query_wide_nearest(const WideNode* nodes, const Vec3d& point, double radius,
                        OnLeaf&& on_leaf) {
    if (!(radius >= 0.0)) {
        return;
    }
    QueryBox q(query_box_around(point, radius));
    const Vec3f p = vec3_cast<float>(point);
    std::int32_t stack[TRAVERSAL_STACK];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const WideNode& node = nodes[stack[--top]];
        unsigned mask = slot_mask(node, q, -1);
        if (mask == 0) {
            continue;
        }
        float gap2[WIDTH];
        slot_gaps(node, p, gap2);
        int order[WIDTH];  // overlapping slots, nearest first (insertion sort of at most 4)
        int count = 0;
        for (unsigned m = mask; m != 0; m &= m - 1) {
            const int k = std::countr_zero(m);
            int at = count++;
            while (at > 0 && gap2[order[at - 1]] > gap2[k]) {
                order[at] = order[at - 1];
                --at;
            }
            order[at] = k;
        }
        // Leaves nearest first; when the radius shrinks, the remaining slots are re-tested.
        for (int i = 0; i < count; ++i) {
            const int k = order[i];
            const std::int32_t c = node.child[k];
            if (!is_leaf(c) || ((mask >> k) & 1u) == 0) {
                continue;
            }
            const double shrunk = on_leaf(leaf_position(c), node.box(k));
            if (shrunk < radius) {
                radius = shrunk;
                q = QueryBox(query_box_around(point, radius));
                mask &= slot_mask(node, q, -1);
            }
        }
        // Inner children farthest first onto the stack, so the nearest is popped next.
        for (int i = count - 1; i >= 0; --i) {
            const int k = order[i];
            const std::int32_t c = node.child[k];
            if (!is_leaf(c) && ((mask >> k) & 1u) != 0) {
                stack[top++] = c;
            }
        }
    }
}

// The leaf slots of a wide node as a query cluster: the union of their boxes and the first
// position. Returns false when the node has no leaf slot.
PLIANT_HOST_DEVICE inline bool leaf_cluster(const WideNode& node, AABB& box, std::int32_t& first) {
    first = INT32_MAX;
    for (int k = 0; k < WIDTH; ++k) {
        if (node.child[k] < 0 && node.child[k] != EMPTY_SLOT) {
            box.extend(node.box(k));
            first = first < node.last[k] ? first : node.last[k];
        }
    }
    return first != INT32_MAX;
}

// Number of output chunks the queries below use when `tree` provides the clusters (the tree
// itself for self queries, tree_a for pair queries): size a ChunkedBuffer with it.
inline std::int64_t num_overlap_chunks(const LBVH& tree) {
    return num_chunks(static_cast<std::int64_t>(tree.nodes().size()), CLUSTER_GRAIN);
}

// visit(chunk, a, b) for every unordered overlapping pair of primitives of `tree`, exactly once
// (a earlier than b in Morton order).
template <typename Visit>
void for_each_self_overlap(const LBVH& tree, Visit&& visit) {
    const WideNode* nodes = tree.nodes().data();
    const std::uint32_t* prims = tree.primitives().data();
    parallel_for_chunks(
        static_cast<std::int64_t>(tree.nodes().size()), CLUSTER_GRAIN,
        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
            for (std::int64_t w = begin; w < end; ++w) {
                const WideNode& cluster = nodes[w];
                AABB cluster_box;
                std::int32_t first = 0;
                if (!leaf_cluster(cluster, cluster_box, first)) {
                    continue;
                }
                query_wide(nodes, cluster_box, first, [&](std::int32_t j, const AABB& box_j) {
                    unsigned mask = leaf_slot_mask(cluster, QueryBox(box_j), j);
                    while (mask != 0) {
                        const int k = std::countr_zero(mask);
                        mask &= mask - 1;
                        visit(chunk, prims[cluster.last[k]], prims[j]);
                    }
                });
            }
        });
}

// visit(chunk, a, b) for every a in tree_a, b in tree_b with overlapping boxes.
template <typename Visit>
void for_each_overlap(const LBVH& tree_a, const LBVH& tree_b, Visit&& visit) {
    if (!tree_b.has_nodes()) {
        return;
    }
    const WideNode* nodes_a = tree_a.nodes().data();
    const WideNode* nodes_b = tree_b.nodes().data();
    const std::uint32_t* prims_a = tree_a.primitives().data();
    const std::uint32_t* prims_b = tree_b.primitives().data();
    parallel_for_chunks(
        static_cast<std::int64_t>(tree_a.nodes().size()), CLUSTER_GRAIN,
        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
            for (std::int64_t w = begin; w < end; ++w) {
                const WideNode& cluster = nodes_a[w];
                AABB cluster_box;
                std::int32_t first = 0;
                if (!leaf_cluster(cluster, cluster_box, first)) {
                    continue;
                }
                query_wide(nodes_b, cluster_box, -1, [&](std::int32_t j, const AABB& box_j) {
                    unsigned mask = leaf_slot_mask(cluster, QueryBox(box_j), INT32_MAX);
                    while (mask != 0) {
                        const int k = std::countr_zero(mask);
                        mask &= mask - 1;
                        visit(chunk, prims_a[cluster.last[k]], prims_b[j]);
                    }
                });
            }
        });
}

struct PrimitivePair {
    std::uint32_t first;
    std::uint32_t second;
    friend constexpr auto operator<=>(const PrimitivePair&, const PrimitivePair&) = default;
};

// Collects the self-overlapping pairs that `accept(a, b)` keeps into `out` (cleared first), in the
// deterministic order above. Keeps its per-chunk buffers between calls.
class SelfOverlapCollector {
public:
    template <typename Accept>
    void collect(const LBVH& tree, Accept&& accept, std::vector<PrimitivePair>& out) {
        m_buffer.reset(num_overlap_chunks(tree));
        for_each_self_overlap(tree, [&](std::int64_t chunk, std::uint32_t a, std::uint32_t b) {
            if (accept(a, b)) {
                m_buffer.chunk(chunk).push_back({a, b});
            }
        });
        m_buffer.gather(out);
    }

private:
    ChunkedBuffer<PrimitivePair> m_buffer;
};

}  // namespace pliant::bvh
