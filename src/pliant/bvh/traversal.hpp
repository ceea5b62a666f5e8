// Overlap queries on LBVHs: all pairs of primitives whose boxes overlap (closed intervals).
//
// Self: every unordered pair {a, b}, a ≠ b, of one tree, reported exactly once. Each leaf i queries
// the tree with its own box and keeps only leaves j > i, pruning every subtree whose leaf range
// ends at or before i — half the work of a plain per-leaf query, no duplicates by construction.
// Pair: every (a, b), a from tree A, b from tree B; each leaf of A queries B.
//
// Kernels are per leaf, GPU style (fixed-size stack, no allocation); the 4-wide nodes are tested
// with SSE where available (x86-64 always has SSE2), a scalar loop otherwise. Output goes through a visitor
// called as visit(chunk, a, b) with primitive ids; leaves are processed in fixed chunks in Morton
// order and, within a leaf, in traversal order, so a visitor that appends to per-chunk buffers
// (ChunkedBuffer) yields a result identical for 1 and N threads.
#pragma once

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <bit>
#include <cstdint>
#include <utility>
#include <vector>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::bvh {

// Deep enough for any LBVH: the wide tree has depth ≤ 63 (see lbvh.hpp) and every pop pushes at
// most WIDTH entries, so the stack never holds more than 3 · 63 + 1.
inline constexpr int TRAVERSAL_STACK = 192;
inline constexpr std::int64_t QUERY_GRAIN = 256;
inline constexpr std::int64_t CLUSTER_GRAIN = 128;

// A query box prepared for repeated slot tests.
struct QueryBox {
#if defined(__SSE2__)
    __m128 lo_x, lo_y, lo_z, hi_x, hi_y, hi_z;
    explicit QueryBox(const AABB& b)
        : lo_x(_mm_set1_ps(b.lo.x)), lo_y(_mm_set1_ps(b.lo.y)), lo_z(_mm_set1_ps(b.lo.z)),
          hi_x(_mm_set1_ps(b.hi.x)), hi_y(_mm_set1_ps(b.hi.y)), hi_z(_mm_set1_ps(b.hi.z)) {}
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

// Visits the tree from the root: on_leaf(j) for every leaf j > after whose box overlaps the query,
// pruning slots whose leaves all come at or before `after`. Leaves are reported in a fixed order
// that depends only on the tree and the query.
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
                on_leaf(leaf_position(c));
            } else {
                stack[top++] = c;
            }
        }
    }
}

// Bit k set when slot k is a leaf at a position before `position` whose box overlaps the query.
PLIANT_HOST_DEVICE PLIANT_FORCE_INLINE unsigned leaf_slots_before(const WideNode& node,
                                                                  const QueryBox& q,
                                                                  std::int32_t position) {
#if defined(__SSE2__)
    const __m128i children = _mm_load_si128(reinterpret_cast<const __m128i*>(node.child));
    const __m128i last = _mm_load_si128(reinterpret_cast<const __m128i*>(node.last));
    // Leaves have child < 0 (unused slots too, but their last is -1 and their box empty).
    const __m128i is_leaf_before = _mm_and_si128(_mm_cmplt_epi32(children, _mm_setzero_si128()),
                                                 _mm_cmplt_epi32(last, _mm_set1_epi32(position)));
    const auto before = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(is_leaf_before)));
    return before & slot_mask(node, q, -1);
#else
    unsigned mask = 0;
    for (int k = 0; k < WIDTH; ++k) {
        mask |= (node.child[k] < 0 && node.last[k] < position && overlaps(node.box(k), q.box) ? 1u : 0u) << k;
    }
    return mask;
#endif
}

// Number of output chunks for_each_self_overlap uses for `tree` (size a ChunkedBuffer with it).
inline std::int64_t num_self_overlap_chunks(const LBVH& tree) {
    return num_chunks(static_cast<std::int64_t>(tree.nodes().size()), CLUSTER_GRAIN);
}

// visit(chunk, a, b) for every unordered overlapping pair of primitives of `tree`, exactly once.
//
// Leaf clusters: the leaf slots of each wide node (up to four leaves, neighbours in Morton order)
// query the tree together with the union of their boxes, pruning subtrees that end before the
// cluster's first leaf; every leaf j found is then tested against the cluster's leaves before it
// in one SIMD step. This walks the upper tree once per cluster instead of once per leaf.
// Chunks are fixed runs of CLUSTER_GRAIN wide nodes (num_self_overlap_chunks).
template <typename Visit>
void for_each_self_overlap(const LBVH& tree, Visit&& visit) {
    if (!tree.has_nodes()) {
        return;
    }
    const WideNode* nodes = tree.nodes().data();
    const AABB* boxes = tree.leaf_boxes().data();
    const std::uint32_t* prims = tree.primitives().data();
    parallel_for_chunks(
        static_cast<std::int64_t>(tree.nodes().size()), CLUSTER_GRAIN,
        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
            for (std::int64_t w = begin; w < end; ++w) {
                const WideNode& cluster = nodes[w];
                AABB cluster_box;
                std::int32_t first = INT32_MAX;
                for (int k = 0; k < WIDTH; ++k) {
                    if (cluster.child[k] < 0 && cluster.child[k] != EMPTY_SLOT) {
                        cluster_box.extend(cluster.box(k));
                        first = first < cluster.last[k] ? first : cluster.last[k];
                    }
                }
                if (first == INT32_MAX) {
                    continue;
                }
                query_wide(nodes, cluster_box, first, [&](std::int32_t j) {
                    const QueryBox q(boxes[j]);
                    unsigned mask = leaf_slots_before(cluster, q, j);
                    while (mask != 0) {
                        const int k = std::countr_zero(mask);
                        mask &= mask - 1;
                        visit(chunk, prims[cluster.last[k]], prims[j]);
                    }
                });
            }
        });
}

// visit(chunk, a, b) for every a in tree_a, b in tree_b with overlapping boxes. Chunks are fixed
// runs of QUERY_GRAIN leaves of tree_a.
template <typename Visit>
void for_each_overlap(const LBVH& tree_a, const LBVH& tree_b, Visit&& visit) {
    if (tree_a.num_primitives() == 0 || tree_b.num_primitives() == 0) {
        return;
    }
    const WideNode* nodes_b = tree_b.nodes().data();
    const bool single_b = !tree_b.has_nodes();
    const AABB* boxes_a = tree_a.leaf_boxes().data();
    const AABB* boxes_b = tree_b.leaf_boxes().data();
    const std::uint32_t* prims_a = tree_a.primitives().data();
    const std::uint32_t* prims_b = tree_b.primitives().data();
    parallel_for_chunks(tree_a.num_primitives(), QUERY_GRAIN,
                        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
                            for (auto i = static_cast<std::int32_t>(begin); i < end; ++i) {
                                const std::uint32_t a = prims_a[i];
                                if (single_b) {  // a single primitive in tree_b
                                    if (overlaps(boxes_a[i], boxes_b[0])) {
                                        visit(chunk, a, prims_b[0]);
                                    }
                                    continue;
                                }
                                query_wide(nodes_b, boxes_a[i], -1, [&](std::int32_t j) {
                                    visit(chunk, a, prims_b[j]);
                                });
                            }
                        });
}

using PrimitivePair = std::pair<std::uint32_t, std::uint32_t>;

// Collects the self-overlapping pairs that `accept(a, b)` keeps into `out` (cleared first), in the
// deterministic order above. Keeps its per-chunk buffers between calls.
class SelfOverlapCollector {
public:
    template <typename Accept>
    void collect(const LBVH& tree, Accept&& accept, std::vector<PrimitivePair>& out) {
        m_buffer.reset(num_self_overlap_chunks(tree));
        for_each_self_overlap(tree, [&](std::int64_t chunk, std::uint32_t a, std::uint32_t b) {
            if (accept(a, b)) {
                m_buffer.chunk(chunk).emplace_back(a, b);
            }
        });
        m_buffer.gather(out);
    }

private:
    ChunkedBuffer<PrimitivePair> m_buffer;
};

}  // namespace pliant::bvh
