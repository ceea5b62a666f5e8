#include "pliant/bvh/lbvh.hpp"

#include <fmt/format.h>

#include <atomic>
#include <limits>

#include "pliant/bvh/morton.hpp"
#include "pliant/core/check.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/core/scan.hpp"

namespace pliant::bvh {
namespace {

constexpr std::int64_t LEAF_GRAIN = 1 << 12;
constexpr std::int64_t WIDE_GRAIN = 1 << 10;
// Subtrees refitted as separate tasks: enough for load balance, each a few thousand nodes at 1M.
constexpr std::int32_t REFIT_SUBTREES = 256;
constexpr std::int64_t COLLAPSE_GRAIN = 1 << 10;
constexpr std::int32_t NO_BOUND = -1;

// Dissimilarity of neighbouring leaves i and i+1: Morton XOR in the high word, position XOR in the
// low word (ties between equal codes). The node splitting at i is the parent of a range [l, r]
// exactly when its δ is the smaller of the two range ends' (Apetrei 2014, Algorithm 1).
PLIANT_HOST_DEVICE inline std::uint64_t delta(const std::uint32_t* keys, std::int32_t i) {
    const auto position_xor = static_cast<std::uint64_t>(static_cast<std::uint32_t>(i ^ (i + 1)));
    return (static_cast<std::uint64_t>(keys[i] ^ keys[i + 1]) << 32) | position_xor;
}

std::int32_t atomic_exchange(std::int32_t& slot, std::int32_t value) {
    return std::atomic_ref<std::int32_t>(slot).exchange(value, std::memory_order_acq_rel);
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
    const auto inverse = [](float e) {
        return e > 0.0f ? 1.0f / e : 0.0f;
    };
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
    m_sorter.sort(std::span(m_keys), std::span(m_primitives), MORTON_BITS);
}

void LBVH::build_hierarchy() {
    const std::int32_t n = num_primitives();
    m_nodes.resize(static_cast<std::size_t>(n - 1));
    m_counters.assign(static_cast<std::size_t>(n - 1), NO_BOUND);
    const std::uint32_t* keys = m_keys.data();
    Node* nodes = m_nodes.data();
    std::int32_t root = -1;

    // Every leaf climbs; at each node the first arrival stores its range end and stops, the second
    // learns the full range and goes on. Boxes are not needed here: the wide tree gets them from
    // a refit once it is collapsed. A node whose children are both leaves needs no atomic: each
    // leaf sees that its neighbour chooses the same parent, the left one goes on, the right one
    // stops (about half of the exchanges of a balanced tree).
    const auto chooses_right_parent = [keys, n](std::int32_t l, std::int32_t r) {
        return l == 0 || (r != n - 1 && delta(keys, r) < delta(keys, l - 1));
    };
    parallel_for(
        n,
        [&](std::int64_t leaf) {
            auto l = static_cast<std::int32_t>(leaf);
            std::int32_t r = l;
            std::int32_t current = leaf_reference(l);
            for (;;) {
                const bool is_left_child = chooses_right_parent(l, r);
                const std::int32_t parent = is_left_child ? r : l - 1;
                Node& node = nodes[parent];
                node.child[is_left_child ? 0 : 1] = current;
                std::int32_t other = NO_BOUND;
                if (l == r && is_left_child && !chooses_right_parent(r + 1, r + 1)) {
                    other = r + 1;  // the sibling is leaf r + 1; this leaf goes on
                } else if (l == r && !is_left_child && chooses_right_parent(l - 1, l - 1)) {
                    return;  // the sibling is leaf l - 1, which goes on
                } else {
                    other = atomic_exchange(m_counters[static_cast<std::size_t>(parent)],
                                            is_left_child ? l : r);
                }
                if (other == NO_BOUND) {
                    return;
                }
                (is_left_child ? r : l) = other;
                node.first = l;
                node.last = r;
                current = parent;
                if (l == 0 && r == n - 1) {
                    root = parent;
                    return;
                }
            }
        },
        LEAF_GRAIN);
    m_root = root;
}

void LBVH::collapse() {
    // Breadth first over the binary tree, one parallel pass per level (GPU style): each wide node
    // starts with the two children of its binary node and repeatedly opens the internal slot with
    // the most leaves (the widest subtree, for a mesh of similar triangles the largest) until it
    // has four slots or only leaves; a prefix sum over the level's internal-slot counts places the
    // next level. Boxes are filled afterwards by refit.
    // Storage grows level by level (geometric reallocation) to the tree's real size, between
    // about n / 3 and n / 2 nodes (0.50 n for the folded sheets of the benchmark).
    const Node* binary = m_nodes.data();
    m_wide_source.resize(1);
    m_wide_source[0] = m_root;
    m_level_offsets.assign(1, 0);
    std::int32_t begin = 0;
    std::int32_t end = 1;
    while (begin < end) {
        m_level_offsets.push_back(end);
        if (m_wide.size() < static_cast<std::size_t>(end)) {
            m_wide.resize(static_cast<std::size_t>(end));
            m_slot_counts.resize(static_cast<std::size_t>(end));
        }
        m_wide_source.resize(static_cast<std::size_t>(end) +
                             static_cast<std::size_t>(WIDTH) *
                                 static_cast<std::size_t>(end - begin));
        WideNode* wide = m_wide.data();
        std::int32_t* source = m_wide_source.data();
        std::int32_t* counts = m_slot_counts.data();
        // Step 1: choose the slots of every node of this level; internal slots keep their binary
        // node in child[k] for now.
        parallel_for(
            end - begin,
            [&](std::int64_t offset) {
                const auto w = static_cast<std::int32_t>(begin + offset);
                // Binary node p splits its range between positions p and p + 1; slot k covers leaf
                // positions [firsts[k], lasts[k]].
                const std::int32_t split = source[w];
                const Node& root = binary[split];
                std::int32_t refs[WIDTH] = {root.child[0], root.child[1]};
                std::int32_t firsts[WIDTH] = {root.first, split + 1};
                std::int32_t lasts[WIDTH] = {split, root.last};
                int count = 2;
                while (count < WIDTH) {
                    int open = -1;
                    for (int k = 0; k < count; ++k) {
                        if (!is_leaf(refs[k]) &&
                            (open < 0 || lasts[k] - firsts[k] > lasts[open] - firsts[open])) {
                            open = k;
                        }
                    }
                    if (open < 0) {
                        break;
                    }
                    const std::int32_t opened_split = refs[open];
                    const std::int32_t opened_last = lasts[open];
                    const Node& opened = binary[opened_split];
                    for (int k = count; k > open + 1; --k) {
                        refs[k] = refs[k - 1];
                        firsts[k] = firsts[k - 1];
                        lasts[k] = lasts[k - 1];
                    }
                    refs[open] = opened.child[0];
                    refs[open + 1] = opened.child[1];
                    lasts[open] = opened_split;
                    firsts[open + 1] = opened_split + 1;
                    lasts[open + 1] = opened_last;
                    ++count;
                }
                WideNode& node = wide[w];
                std::int32_t internal = 0;
                for (int k = 0; k < WIDTH; ++k) {
                    if (k >= count) {
                        node.set_box(k, AABB{});
                        node.child[k] = EMPTY_SLOT;
                        node.last[k] = -1;
                        continue;
                    }
                    node.child[k] = refs[k];
                    node.last[k] = lasts[k];
                    internal += is_leaf(refs[k]) ? 0 : 1;
                }
                counts[w] = internal;
            },
            COLLAPSE_GRAIN);
        // Step 2: where each node's internal children go on the next level.
        const std::int32_t next =
            exclusive_scan(std::span(counts + begin, static_cast<std::size_t>(end - begin)));
        // Step 3: link the children.
        parallel_for(
            end - begin,
            [&](std::int64_t offset) {
                const auto w = static_cast<std::int32_t>(begin + offset);
                WideNode& node = wide[w];
                std::int32_t at = end + counts[w];
                for (int& k : node.child) {
                    if (k >= 0) {
                        source[at] = k;
                        k = at++;
                    }
                }
            },
            COLLAPSE_GRAIN);
        begin = end;
        end += next;
    }
    m_num_wide = end;
}

void LBVH::build(std::span<const AABB> boxes) {
    if (boxes.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
        throw InvalidInput(fmt::format("LBVH::build: {} boxes, at most {} supported", boxes.size(),
                                       std::numeric_limits<std::int32_t>::max()));
    }
    // A valid box has lo ≤ hi on every axis and a finite extent: hi - lo is NaN or inf for NaN or
    // infinite bounds and negative for an empty box. Checked branch-free, then located if bad.
    const auto is_valid = [](const AABB& b) {
        const Vec3f e = b.hi - b.lo;
        return (int{e.x >= 0.0f} & int{e.y >= 0.0f} & int{e.z >= 0.0f} &
                int{e.x <= std::numeric_limits<float>::max()} &
                int{e.y <= std::numeric_limits<float>::max()} &
                int{e.z <= std::numeric_limits<float>::max()}) != 0;
    };
    const bool all_valid = parallel_reduce(
        static_cast<std::int64_t>(boxes.size()), true,
        [&](std::int64_t begin, std::int64_t end) {
            int valid = 1;
            for (std::int64_t i = begin; i < end; ++i) {
                valid &= int{is_valid(boxes[static_cast<std::size_t>(i)])};
            }
            return valid != 0;
        },
        [](bool a, bool b) { return a && b; }, LEAF_GRAIN);
    if (!all_valid) {
        for (std::size_t i = 0; i < boxes.size(); ++i) {
            const AABB& b = boxes[i];
            if (!is_valid(b)) {
                throw InvalidInput(
                    fmt::format("LBVH::build: box {} is empty, not finite or wider than the float "
                                "range: lo ({}, {}, {}), hi ({}, {}, {})",
                                i, b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z));
            }
        }
    }
    compute_leaf_order(boxes);
    m_root = -1;
    m_num_wide = 0;
    m_level_offsets.clear();
    m_cut_depth = 0;
    m_subtree_offsets.assign(1, 0);
    m_subtree_ranges.clear();
    if (boxes.empty()) {
        return;
    }
    if (boxes.size() == 1) {  // one node, one used slot
        m_wide.resize(1);
        WideNode& node = m_wide[0];
        for (int k = 0; k < WIDTH; ++k) {
            node.set_box(k, AABB{});
            node.child[k] = k == 0 ? leaf_reference(0) : EMPTY_SLOT;
            node.last[k] = k == 0 ? 0 : -1;
        }
        m_num_wide = 1;
        m_level_offsets = {0, 1};
    } else {
        build_hierarchy();
        collapse();
    }
    plan_refit();
    refit(boxes);
}

void LBVH::refit(std::span<const AABB> boxes) {
    if (boxes.size() != m_primitives.size()) {
        throw InvalidInput(
            fmt::format("LBVH::refit: boxes.size() ({}) != primitives in the tree ({})",
                        boxes.size(), m_primitives.size()));
    }
    WideNode* wide = m_wide.data();
    const std::uint32_t* primitives = m_primitives.data();
    const auto refit_node = [&](std::int32_t w) {
        WideNode& node = wide[w];
        for (int k = 0; k < WIDTH; ++k) {
            const std::int32_t c = node.child[k];
            if (c == EMPTY_SLOT) {
                continue;
            }
            node.set_box(k, is_leaf(c) ? boxes[primitives[leaf_position(c)]] : wide[c].bounds());
        }
    };
    // Step 1: the subtrees below the cut, one task each, each bottom-up over its own contiguous
    // ranges (small enough to stay in cache while its levels are refitted).
    const auto num_subtrees = static_cast<std::int64_t>(m_subtree_offsets.size()) - 1;
    detail::run_chunks(num_subtrees, [&](std::int64_t t) {
        const auto first = static_cast<std::size_t>(m_subtree_offsets[static_cast<std::size_t>(t)]);
        const auto last =
            static_cast<std::size_t>(m_subtree_offsets[static_cast<std::size_t>(t) + 1]);
        for (std::size_t r = last; r-- > first;) {  // deepest range first
            for (std::int32_t w = m_subtree_ranges[r][0]; w < m_subtree_ranges[r][1]; ++w) {
                refit_node(w);
            }
        }
    });
    // Step 2: the levels above the cut, deepest first: a node's children are all on deeper
    // levels, already refitted.
    for (int level = m_cut_depth - 1; level >= 0; --level) {
        const std::int32_t begin = m_level_offsets[static_cast<std::size_t>(level)];
        const std::int32_t end = m_level_offsets[static_cast<std::size_t>(level) + 1];
        parallel_for(
            end - begin,
            [&](std::int64_t offset) { refit_node(begin + static_cast<std::int32_t>(offset)); },
            WIDE_GRAIN);
    }
}

void LBVH::plan_refit() {
    // The cut: the first depth with at least REFIT_SUBTREES nodes (or the deepest). Each node of
    // that depth roots a subtree whose nodes at every deeper depth form one contiguous range of
    // the breadth-first order (children are numbered in the order of their parents).
    const int levels = depth();
    m_cut_depth = levels - 1;
    for (int d = 0; d < levels; ++d) {
        if (m_level_offsets[static_cast<std::size_t>(d) + 1] -
                m_level_offsets[static_cast<std::size_t>(d)] >=
            REFIT_SUBTREES) {
            m_cut_depth = d;
            break;
        }
    }
    m_subtree_offsets.assign(1, 0);
    m_subtree_ranges.clear();
    const WideNode* wide = m_wide.data();
    const auto first_internal_child = [&](std::int32_t begin, std::int32_t end) {
        for (std::int32_t w = begin; w < end; ++w) {
            for (int k : wide[w].child) {
                if (k >= 0) {
                    return k;
                }
            }
        }
        return -1;
    };
    const auto last_internal_child = [&](std::int32_t begin, std::int32_t end) {
        for (std::int32_t w = end - 1; w >= begin; --w) {
            for (int k = WIDTH - 1; k >= 0; --k) {
                if (wide[w].child[k] >= 0) {
                    return wide[w].child[k];
                }
            }
        }
        return -1;
    };
    for (std::int32_t root = m_level_offsets[static_cast<std::size_t>(m_cut_depth)];
         root < m_level_offsets[static_cast<std::size_t>(m_cut_depth) + 1]; ++root) {
        std::array<std::int32_t, 2> range{root, root + 1};
        while (range[0] >= 0) {
            m_subtree_ranges.push_back(range);
            const std::int32_t first = first_internal_child(range[0], range[1]);
            range = {first, first < 0 ? -1 : last_internal_child(range[0], range[1]) + 1};
        }
        m_subtree_offsets.push_back(static_cast<std::int32_t>(m_subtree_ranges.size()));
    }
}

AABB LBVH::bounds() const {
    if (has_nodes()) {
        return m_wide.front().bounds();
    }
    return AABB{};
}

std::size_t LBVH::memory_bytes() const {
    return m_wide.capacity() * sizeof(WideNode) +
           m_level_offsets.capacity() * sizeof(std::int32_t) +
           m_slot_counts.capacity() * sizeof(std::int32_t) +
           m_wide_source.capacity() * sizeof(std::int32_t) + m_nodes.capacity() * sizeof(Node) +
           m_subtree_offsets.capacity() * sizeof(std::int32_t) +
           m_subtree_ranges.capacity() * sizeof(std::array<std::int32_t, 2>) +
           m_primitives.capacity() * sizeof(std::uint32_t) +
           m_keys.capacity() * sizeof(std::uint32_t) +
           m_counters.capacity() * sizeof(std::int32_t) + m_sorter.memory_bytes();
}

void LBVH::validate(std::span<const AABB> boxes) const {
    const std::int32_t n = num_primitives();
    PLIANT_CHECK_EQ(boxes.size(), static_cast<std::size_t>(n));
    if (n == 0) {
        PLIANT_CHECK(!has_nodes());
        return;
    }
    // Depth-first over the wide tree carrying each node's expected leaf range and depth; checks
    // ranges and breadth-first placement, then boxes bottom-up.
    struct Item {
        std::int32_t node, first, last, depth;
    };
    std::vector<Item> stack{{0, 0, n - 1, 0}};
    std::vector<int> leaf_seen(static_cast<std::size_t>(n), 0);
    std::vector<int> node_seen(static_cast<std::size_t>(m_num_wide), 0);
    std::vector<std::int32_t> order;
    while (!stack.empty()) {
        const Item item = stack.back();
        stack.pop_back();
        PLIANT_CHECK_LT(static_cast<std::size_t>(item.depth) + 1, m_level_offsets.size());
        PLIANT_CHECK(item.node >= m_level_offsets[static_cast<std::size_t>(item.depth)] &&
                     item.node < m_level_offsets[static_cast<std::size_t>(item.depth) + 1]);
        ++node_seen[static_cast<std::size_t>(item.node)];
        order.push_back(item.node);
        const WideNode& node = m_wide[static_cast<std::size_t>(item.node)];
        std::int32_t next = item.first;
        int used = 0;
        for (int k = 0; k < WIDTH; ++k) {
            const std::int32_t c = node.child[k];
            if (c == EMPTY_SLOT) {
                PLIANT_CHECK(node.box(k).is_empty() && node.last[k] == -1);
                continue;
            }
            PLIANT_CHECK_EQ(k, used);  // used slots first
            ++used;
            PLIANT_CHECK_GE(node.last[k], next);
            if (is_leaf(c)) {
                PLIANT_CHECK_EQ(leaf_position(c), next);
                PLIANT_CHECK_EQ(node.last[k], next);
                ++leaf_seen[static_cast<std::size_t>(next)];
                PLIANT_CHECK(node.box(k) == boxes[m_primitives[static_cast<std::size_t>(next)]]);
            } else {
                PLIANT_CHECK(c > item.node && c < m_num_wide);
                PLIANT_CHECK(node.box(k) == m_wide[static_cast<std::size_t>(c)].bounds());
                stack.push_back({c, next, node.last[k], item.depth + 1});
            }
            next = node.last[k] + 1;
        }
        PLIANT_CHECK_GE(used, n == 1 ? 1 : 2);
        PLIANT_CHECK_EQ(next, item.last + 1);
    }
    for (std::int32_t p = 0; p < n; ++p) {
        PLIANT_CHECK_EQ(leaf_seen[static_cast<std::size_t>(p)], 1);
    }
    for (const int seen : node_seen) {
        PLIANT_CHECK_EQ(seen, 1);
    }
    // Every node box equals the merge of its subtree's leaf boxes: by induction, since every slot
    // box equals its child's bounds and leaf slots equal the leaf boxes (checked above).
    PLIANT_CHECK_EQ(order.size(), static_cast<std::size_t>(m_num_wide));
}

void LBVH::save_state(ByteWriter& out) const {
    // The tree and its refit plan; the build's scratch (binary nodes, keys, counters) is rebuilt
    // by the next build.
    out.put_vector(std::span(m_wide).first(static_cast<std::size_t>(m_num_wide)));
    out.put_vector(m_level_offsets);
    out.put(m_cut_depth);
    out.put_vector(m_subtree_offsets);
    out.put_vector(m_subtree_ranges);
    out.put_vector(m_primitives);
}

void LBVH::load_state(ByteReader& in) {
    in.get_vector("bvh.wide", m_wide);
    m_num_wide = static_cast<std::int32_t>(m_wide.size());
    in.get_vector("bvh.level_offsets", m_level_offsets);
    m_cut_depth = in.get<int>("bvh.cut_depth");
    in.get_vector("bvh.subtree_offsets", m_subtree_offsets);
    in.get_vector("bvh.subtree_ranges", m_subtree_ranges);
    in.get_vector("bvh.primitives", m_primitives);
    for (const std::int32_t offset : m_subtree_offsets) {
        if (offset < 0 || static_cast<std::size_t>(offset) > m_subtree_ranges.size()) {
            throw InvalidInput(fmt::format("{}: bvh.subtree_offsets: {} of {} ranges", in.source(),
                                           offset, m_subtree_ranges.size()));
        }
    }
    for (const std::array<std::int32_t, 2>& range : m_subtree_ranges) {
        if (range[0] < 0 || range[0] > range[1] || range[1] > m_num_wide) {
            throw InvalidInput(fmt::format("{}: bvh.subtree_ranges: [{}, {}) of {} nodes",
                                           in.source(), range[0], range[1], m_num_wide));
        }
    }
}

}  // namespace pliant::bvh
