// LBVH: a linear bounding volume hierarchy over boxes the caller owns, built and refitted in
// parallel, GPU style (Morton-ordered radix tree of Karras 2012, built bottom-up after Apetrei
// 2014, "Fast and Simple Agglomerative LBVH Construction").
//
// build(boxes): Morton codes of box centres (30 bits) → parallel radix sort → one bottom-up pass in
// which every leaf climbs until it is the first to reach a node (an atomic exchange of range ends
// decides who goes on; a node with two leaf children needs none), writing child links and leaf
// ranges. Sorted positions break ties between equal Morton codes, so the tree is a radix tree
// over distinct 62-bit keys: depth ≤ 63, identical boxes give a balanced tree. The binary
// topology is then collapsed into a 4-wide tree (wide_node.hpp), breadth first, each node opening
// the children with the most leaves, and its boxes are filled by refit; queries traverse the wide
// tree with one SIMD test per four boxes. O(n) work, deterministic for any number of threads.
//
// refit(boxes): new boxes for the same primitives, hierarchy kept. The subtrees below a cut depth
// are refitted as independent tasks, each bottom-up over its own contiguous node ranges (cache
// friendly), then the few levels above the cut, one parallel loop per depth. O(n). Boxes are
// merged with exact min/max, so the result is bitwise independent of scheduling.
//
// Leaf boxes live only in the wide nodes' slots (no separate copy): queries read them there.
// Preconditions: boxes finite and non-empty (checked by build, not by refit: refit is the per-step
// hot path; a NaN box there only makes overlaps fail). At most 2^31 - 1 boxes. The LBVH does not
// keep a reference to the caller's boxes between calls.
// Thread safety: build/refit must not run concurrently with anything else on the same LBVH;
// const queries may run concurrently.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/bvh/node.hpp"
#include "pliant/bvh/wide_node.hpp"
#include "pliant/core/aabb.hpp"
#include "pliant/core/bytes.hpp"
#include "pliant/core/radix_sort.hpp"

namespace pliant::bvh {

class LBVH {
public:
    void build(std::span<const AABB> boxes);
    void refit(std::span<const AABB> boxes);

    std::int32_t num_primitives() const { return static_cast<std::int32_t>(m_primitives.size()); }
    // True when there is at least one primitive; the root is nodes()[0] (a single primitive is one
    // node with one used slot).
    bool has_nodes() const { return m_num_wide > 0; }
    // The wide tree, breadth first (root at 0).
    std::span<const WideNode> nodes() const {
        return std::span(m_wide).first(static_cast<std::size_t>(m_num_wide));
    }
    // Depth of the wide tree (0 without primitives).
    int depth() const {
        return m_level_offsets.empty() ? 0 : static_cast<int>(m_level_offsets.size()) - 1;
    }
    // Primitive (index into the caller's boxes) at each leaf position (Morton order).
    std::span<const std::uint32_t> primitives() const { return m_primitives; }
    // Box of everything (empty box when there are no primitives).
    AABB bounds() const;
    // Bytes held (wide nodes, permutation, build scratch).
    std::size_t memory_bytes() const;

    // Checks every structural invariant against the boxes of the last build/refit — each leaf
    // reached exactly once, slot ranges tile their node's range in order, `last` of each slot,
    // breadth-first order, leaf slots holding boxes[primitive], every other slot the bounds of its
    // child — and throws InternalError naming the first violation. O(n); for tests.
    void validate(std::span<const AABB> boxes) const;

    // The tree and its refit plan (core/bytes.hpp), so that a run resumed from a checkpoint
    // refits the same tree bit for bit. load_state throws InvalidInput for a truncated state.
    void save_state(ByteWriter& out) const;
    void load_state(ByteReader& in);

private:
    void compute_leaf_order(std::span<const AABB> boxes);
    void build_hierarchy();
    void collapse();
    void plan_refit();

    std::vector<WideNode> m_wide;  // the traversal tree (first m_num_wide used)
    std::int32_t m_num_wide = 0;
    std::vector<std::int32_t> m_level_offsets;  // depth d holds m_wide[offsets[d] .. offsets[d+1])
    // Refit plan: below m_cut_depth, subtree t owns the node ranges
    // m_subtree_ranges[m_subtree_offsets[t] .. m_subtree_offsets[t+1]), shallowest first.
    int m_cut_depth = 0;
    std::vector<std::int32_t> m_subtree_offsets;
    std::vector<std::array<std::int32_t, 2>> m_subtree_ranges;
    std::vector<std::uint32_t> m_primitives;  // n, Morton order → primitive id
    // Build scratch, kept to avoid reallocation between builds.
    std::vector<Node> m_nodes;                // n - 1 binary nodes
    std::vector<std::uint32_t> m_keys;        // n Morton codes, sorted
    std::vector<std::int32_t> m_counters;     // n - 1 atomics: range ends
    std::vector<std::int32_t> m_wide_source;  // binary node each wide node is collapsed from
    std::vector<std::int32_t> m_slot_counts;  // internal slots per wide node
    std::int32_t m_root = -1;                 // binary root
    RadixSorter m_sorter;
};

}  // namespace pliant::bvh
