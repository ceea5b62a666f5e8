#include "brute_force.hpp"

#include <algorithm>

namespace pliant::test {

std::vector<Pair> brute_force_self_overlaps(std::span<const AABB> boxes) {
    std::vector<Pair> pairs;
    for (std::uint32_t a = 0; a < boxes.size(); ++a) {
        for (std::uint32_t b = a + 1; b < boxes.size(); ++b) {
            if (overlaps(boxes[a], boxes[b])) {
                pairs.emplace_back(a, b);
            }
        }
    }
    return pairs;
}

std::vector<Pair> brute_force_overlaps(std::span<const AABB> boxes_a,
                                       std::span<const AABB> boxes_b) {
    std::vector<Pair> pairs;
    for (std::uint32_t a = 0; a < boxes_a.size(); ++a) {
        for (std::uint32_t b = 0; b < boxes_b.size(); ++b) {
            if (overlaps(boxes_a[a], boxes_b[b])) {
                pairs.emplace_back(a, b);
            }
        }
    }
    return pairs;
}

std::vector<Pair> normalized(std::vector<Pair> pairs) {
    for (Pair& p : pairs) {
        if (p.first > p.second) {
            std::swap(p.first, p.second);
        }
    }
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

}  // namespace pliant::test
