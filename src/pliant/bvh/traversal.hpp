// Overlap queries on LBVHs: all pairs of primitives whose boxes overlap (closed intervals).
//
// Self: every unordered pair {a, b}, a ≠ b, of one tree, reported exactly once. Each leaf i queries
// the tree with its own box and keeps only leaves j > i, pruning every subtree whose leaf range
// ends at or before i — half the work of a plain per-leaf query, no duplicates by construction.
// Pair: every (a, b), a from tree A, b from tree B; each leaf of A queries B.
//
// Kernels are per leaf, GPU style (fixed-size stack, no allocation). Output goes through a visitor
// called as visit(chunk, a, b) with primitive ids; leaves are processed in fixed chunks in Morton
// order and, within a leaf, in traversal order, so a visitor that appends to per-chunk buffers
// (ChunkedBuffer) yields a result identical for 1 and N threads.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "pliant/bvh/lbvh.hpp"
#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::bvh {

// Deep enough for any LBVH: depth ≤ 63 (see lbvh.hpp) and the stack holds at most depth + 1.
inline constexpr int TRAVERSAL_STACK = 64;
inline constexpr std::int64_t QUERY_GRAIN = 256;

// Leaves j > i of the tree rooted at `root` whose boxes overlap `query`: on_leaf(j) in traversal
// order. `last_of_root` is the root's last leaf position.
template <typename OnLeaf>
PLIANT_HOST_DEVICE void query_leaves_after(const Node* nodes, std::int32_t root, const AABB& query,
                                           std::int32_t i, OnLeaf&& on_leaf) {
    std::int32_t stack[TRAVERSAL_STACK];
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
        const Node& node = nodes[stack[--top]];
        const std::int32_t split = static_cast<std::int32_t>(&node - nodes);
        // Right child first onto the stack so the left one is visited first (Morton order).
        if (node.last > i && overlaps(node.box[1], query)) {
            const std::int32_t c = node.child[1];
            if (is_leaf(c)) {
                on_leaf(leaf_position(c));
            } else {
                stack[top++] = c;
            }
        }
        if (split > i && overlaps(node.box[0], query)) {
            const std::int32_t c = node.child[0];
            if (is_leaf(c)) {
                on_leaf(leaf_position(c));
            } else {
                stack[top++] = c;
            }
        }
    }
}

// All leaves of the tree whose boxes overlap `query`: on_leaf(j).
template <typename OnLeaf>
PLIANT_HOST_DEVICE void query_leaves(const Node* nodes, std::int32_t root, const AABB& query,
                                     OnLeaf&& on_leaf) {
    std::int32_t stack[TRAVERSAL_STACK];
    int top = 0;
    stack[top++] = root;
    while (top > 0) {
        const Node& node = nodes[stack[--top]];
        for (int s = 1; s >= 0; --s) {
            if (overlaps(node.box[s], query)) {
                const std::int32_t c = node.child[s];
                if (is_leaf(c)) {
                    on_leaf(leaf_position(c));
                } else {
                    stack[top++] = c;
                }
            }
        }
    }
}

// visit(chunk, a, b) for every unordered overlapping pair of primitives of `tree` (a is the one
// earlier in Morton order). Chunks are fixed runs of QUERY_GRAIN leaves.
template <typename Visit>
void for_each_self_overlap(const LBVH& tree, Visit&& visit) {
    const std::int32_t root = tree.root();
    if (root < 0) {
        return;
    }
    const Node* nodes = tree.nodes().data();
    const AABB* boxes = tree.leaf_boxes().data();
    const std::uint32_t* prims = tree.primitives().data();
    parallel_for_chunks(tree.num_primitives(), QUERY_GRAIN,
                        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
                            for (auto i = static_cast<std::int32_t>(begin); i < end; ++i) {
                                const std::uint32_t a = prims[i];
                                query_leaves_after(nodes, root, boxes[i], i, [&](std::int32_t j) {
                                    visit(chunk, a, prims[j]);
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
    const Node* nodes_b = tree_b.nodes().data();
    const std::int32_t root_b = tree_b.root();
    const AABB* boxes_a = tree_a.leaf_boxes().data();
    const AABB* boxes_b = tree_b.leaf_boxes().data();
    const std::uint32_t* prims_a = tree_a.primitives().data();
    const std::uint32_t* prims_b = tree_b.primitives().data();
    parallel_for_chunks(tree_a.num_primitives(), QUERY_GRAIN,
                        [&](std::int64_t chunk, std::int64_t begin, std::int64_t end) {
                            for (auto i = static_cast<std::int32_t>(begin); i < end; ++i) {
                                const std::uint32_t a = prims_a[i];
                                if (root_b < 0) {  // a single primitive in tree_b
                                    if (overlaps(boxes_a[i], boxes_b[0])) {
                                        visit(chunk, a, prims_b[0]);
                                    }
                                    continue;
                                }
                                query_leaves(nodes_b, root_b, boxes_a[i], [&](std::int32_t j) {
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
        m_buffer.reset(num_chunks(tree.num_primitives(), QUERY_GRAIN));
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
