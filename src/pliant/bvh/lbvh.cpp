#include "pliant/bvh/lbvh.hpp"

#include <fmt/format.h>

#include <atomic>
#include <limits>

#include "pliant/bvh/morton.hpp"
#include "pliant/core/check.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant::bvh {
namespace {

constexpr std::int64_t LEAF_GRAIN = 1 << 12;
constexpr std::int32_t NO_BOUND = -1;

// Dissimilarity of neighbouring leaves i and i+1: Morton XOR in the high word, position XOR in the
// low word (ties between equal codes). The node splitting at i is the parent of a range [l, r]
// exactly when its δ is the smaller of the two range ends' (Apetrei 2014, Algorithm 1).
PLIANT_HOST_DEVICE inline std::uint64_t delta(const std::uint64_t* keys, std::int32_t i) {
    const auto position_xor = static_cast<std::uint64_t>(static_cast<std::uint32_t>(i ^ (i + 1)));
    return ((keys[i] ^ keys[i + 1]) << 32) | position_xor;
}

std::int32_t atomic_exchange(std::int32_t& slot, std::int32_t value) {
    return std::atomic_ref<std::int32_t>(slot).exchange(value, std::memory_order_acq_rel);
}

std::int32_t atomic_increment(std::int32_t& slot) {
    return std::atomic_ref<std::int32_t>(slot).fetch_add(1, std::memory_order_acq_rel);
}

}  // namespace

void LBVH::compute_leaf_order(std::span<const AABB> boxes) {
    const auto n = static_cast<std::int64_t>(boxes.size());
    // Step 1: bounds of the box centres.
    const AABB centre_bounds = parallel_reduce(
        n, AABB{},
        [&](std::int64_t begin, std::int64_t end) {
            AABB b;
            for (std::int64_t i = begin; i < end; ++i) {
                b.extend(boxes[static_cast<std::size_t>(i)].center());
            }
            return b;
        },
        [](const AABB& a, const AABB& b) { return merge(a, b); }, LEAF_GRAIN);
    const Vec3f extent = centre_bounds.extent();
    const auto inverse = [](float e) { return e > 0.0f ? 1.0f / e : 0.0f; };
    const Vec3f inv_extent{inverse(extent.x), inverse(extent.y), inverse(extent.z)};

    // Step 2: Morton codes, then a stable sort (equal codes keep primitive order).
    m_keys.resize(boxes.size());
    m_primitives.resize(boxes.size());
    parallel_for(
        n,
        [&](std::int64_t i) {
            const auto k = static_cast<std::size_t>(i);
            m_keys[k] = morton_code(boxes[k].center(), centre_bounds.lo, inv_extent);
            m_primitives[k] = static_cast<std::uint32_t>(i);
        },
        LEAF_GRAIN);
    m_sorter.sort(m_keys, m_primitives, MORTON_BITS);

    m_leaf_boxes.resize(boxes.size());
    parallel_for(
        n, [&](std::int64_t i) {
            m_leaf_boxes[static_cast<std::size_t>(i)] = boxes[m_primitives[static_cast<std::size_t>(i)]];
        },
        LEAF_GRAIN);
}

void LBVH::build_hierarchy() {
    const std::int32_t n = num_primitives();
    m_nodes.resize(static_cast<std::size_t>(n - 1));
    m_leaf_parent.resize(static_cast<std::size_t>(n));
    m_counters.assign(static_cast<std::size_t>(n - 1), NO_BOUND);
    const std::uint64_t* keys = m_keys.data();
    Node* nodes = m_nodes.data();
    std::int32_t root = -1;

    // Every leaf climbs; at each node the first arrival stores its range end and stops, the second
    // learns the full range, merges the two child boxes and goes on.
    parallel_for(
        n,
        [&](std::int64_t leaf) {
            auto l = static_cast<std::int32_t>(leaf);
            std::int32_t r = l;
            std::int32_t current = leaf_reference(l);
            AABB box = m_leaf_boxes[static_cast<std::size_t>(leaf)];
            for (;;) {
                const bool is_left_child = l == 0 || (r != n - 1 && delta(keys, r) < delta(keys, l - 1));
                const std::int32_t parent = is_left_child ? r : l - 1;
                const int slot = is_left_child ? 0 : 1;
                Node& node = nodes[parent];
                node.child[slot] = current;
                node.box[slot] = box;
                const std::int32_t link = (parent << 1) | slot;
                if (is_leaf(current)) {
                    m_leaf_parent[static_cast<std::size_t>(leaf_position(current))] = link;
                } else {
                    nodes[current].parent = link;
                }
                const std::int32_t other =
                    atomic_exchange(m_counters[static_cast<std::size_t>(parent)], is_left_child ? l : r);
                if (other == NO_BOUND) {
                    return;
                }
                (is_left_child ? r : l) = other;
                box = merge(node.box[0], node.box[1]);
                node.last = r;
                current = parent;
                if (l == 0 && r == n - 1) {
                    node.parent = -1;
                    root = parent;
                    return;
                }
            }
        },
        LEAF_GRAIN);
    m_root = root;
    std::fill(m_counters.begin(), m_counters.end(), 0);
}

void LBVH::build(std::span<const AABB> boxes) {
    if (boxes.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
        throw InvalidInput(fmt::format("LBVH::build: {} boxes, at most {} supported", boxes.size(),
                                       std::numeric_limits<std::int32_t>::max()));
    }
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        const AABB& b = boxes[i];
        if (!is_finite(b.lo) || !is_finite(b.hi) || b.is_empty()) {
            throw InvalidInput(fmt::format(
                "LBVH::build: box {} is empty or not finite: lo ({}, {}, {}), hi ({}, {}, {})", i,
                b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z));
        }
    }
    compute_leaf_order(boxes);
    m_root = -1;
    if (boxes.size() < 2) {
        m_nodes.clear();
        m_leaf_parent.assign(boxes.size(), -1);
        m_counters.clear();
        return;
    }
    build_hierarchy();
}

void LBVH::refit(std::span<const AABB> boxes) {
    if (boxes.size() != m_primitives.size()) {
        throw InvalidInput(fmt::format("LBVH::refit: boxes.size() ({}) != primitives in the tree ({})",
                                       boxes.size(), m_primitives.size()));
    }
    const auto n = static_cast<std::int64_t>(boxes.size());
    Node* nodes = m_nodes.data();
    // Every node is visited exactly twice per refit, so counter parity tells the first arrival
    // without resetting the counters.
    parallel_for(
        n,
        [&](std::int64_t leaf) {
            const auto k = static_cast<std::size_t>(leaf);
            AABB box = boxes[m_primitives[k]];
            m_leaf_boxes[k] = box;
            std::int32_t link = m_leaf_parent[k];
            while (link >= 0) {
                Node& node = nodes[link >> 1];
                node.box[link & 1] = box;
                if ((atomic_increment(m_counters[static_cast<std::size_t>(link >> 1)]) & 1) == 0) {
                    return;
                }
                box = merge(node.box[0], node.box[1]);
                link = node.parent;
            }
        },
        LEAF_GRAIN);
}

AABB LBVH::bounds() const {
    if (m_root >= 0) {
        const Node& r = m_nodes[static_cast<std::size_t>(m_root)];
        return merge(r.box[0], r.box[1]);
    }
    return m_leaf_boxes.empty() ? AABB{} : m_leaf_boxes.front();
}

std::size_t LBVH::memory_bytes() const {
    return m_nodes.capacity() * sizeof(Node) + m_leaf_boxes.capacity() * sizeof(AABB) +
           m_primitives.capacity() * sizeof(std::uint32_t) +
           m_leaf_parent.capacity() * sizeof(std::int32_t) +
           m_keys.capacity() * sizeof(std::uint64_t) + m_counters.capacity() * sizeof(std::int32_t);
}

void LBVH::validate() const {
    const std::int32_t n = num_primitives();
    PLIANT_CHECK_EQ(m_leaf_boxes.size(), static_cast<std::size_t>(n));
    if (n < 2) {
        PLIANT_CHECK_EQ(m_root, -1);
        return;
    }
    PLIANT_CHECK(m_root >= 0 && m_root < n - 1);
    PLIANT_CHECK_EQ(m_nodes[static_cast<std::size_t>(m_root)].parent, -1);
    std::vector<int> leaf_seen(static_cast<std::size_t>(n), 0);
    // Iterative DFS carrying each node's expected range and returning its merged box.
    struct Item {
        std::int32_t node, first, last, link;
    };
    std::vector<Item> stack{{m_root, 0, n - 1, -1}};
    std::vector<AABB> subtree_box(static_cast<std::size_t>(n - 1));
    std::vector<std::int32_t> order;
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        const Node& node = m_nodes[static_cast<std::size_t>(item.node)];
        PLIANT_CHECK_EQ(node.parent, item.link);
        PLIANT_CHECK_EQ(node.last, item.last);
        PLIANT_CHECK(item.first <= item.node && item.node < item.last);
        order.push_back(item.node);
        const std::int32_t ranges[2][2] = {{item.first, item.node}, {item.node + 1, item.last}};
        for (int s = 0; s < 2; ++s) {
            const std::int32_t c = node.child[s];
            if (is_leaf(c)) {
                const std::int32_t p = leaf_position(c);
                PLIANT_CHECK(ranges[s][0] == p && ranges[s][1] == p);
                ++leaf_seen[static_cast<std::size_t>(p)];
                PLIANT_CHECK_EQ(m_leaf_parent[static_cast<std::size_t>(p)], (item.node << 1) | s);
                PLIANT_CHECK(node.box[s] == m_leaf_boxes[static_cast<std::size_t>(p)]);
            } else {
                PLIANT_CHECK(ranges[s][0] < ranges[s][1]);
                stack.push_back({c, ranges[s][0], ranges[s][1], (item.node << 1) | s});
            }
        }
    }
    PLIANT_CHECK_EQ(order.size(), static_cast<std::size_t>(n - 1));
    for (std::int32_t p = 0; p < n; ++p) {
        PLIANT_CHECK_EQ(leaf_seen[static_cast<std::size_t>(p)], 1);
    }
    // Boxes: children before parents (reverse DFS pre-order).
    for (auto it = order.rbegin(); it != order.rend(); ++it) {
        const Node& node = m_nodes[static_cast<std::size_t>(*it)];
        for (int s = 0; s < 2; ++s) {
            if (!is_leaf(node.child[s])) {
                PLIANT_CHECK(node.box[s] == subtree_box[static_cast<std::size_t>(node.child[s])]);
            }
        }
        subtree_box[static_cast<std::size_t>(*it)] = merge(node.box[0], node.box[1]);
    }
}

}  // namespace pliant::bvh
