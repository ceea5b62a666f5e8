// The binary LBVH node, built bottom-up (Apetrei 2014) and then collapsed into the 4-wide
// traversal tree (wide_node.hpp): topology only (16 bytes), boxes live in the wide tree.
//
// Leaves are the primitives in Morton order ("leaf positions" 0..n-1). Internal node p splits the
// leaf range [first, last] between positions p and p+1 (Karras 2012 / Apetrei 2014 indexing): its
// left child covers [first, p] and its right child [p+1, last]. A child reference c ≥ 0 is an
// internal node; c < 0 is the leaf at position ~c.
#pragma once

#include <cstdint>
#include <type_traits>

#include "pliant/core/host_device.hpp"

namespace pliant::bvh {

struct Node {
    std::int32_t child[2];  // ≥ 0 internal node index, < 0 leaf position ~c
    std::int32_t first;     // first leaf position of this subtree
    std::int32_t last;      // last leaf position of this subtree
};
static_assert(sizeof(Node) == 16 && std::is_trivially_copyable_v<Node>);

PLIANT_HOST_DEVICE constexpr bool is_leaf(std::int32_t child) {
    return child < 0;
}
PLIANT_HOST_DEVICE constexpr std::int32_t leaf_position(std::int32_t child) {
    return ~child;
}
PLIANT_HOST_DEVICE constexpr std::int32_t leaf_reference(std::int32_t position) {
    return ~position;
}

}  // namespace pliant::bvh
