// Grouping items by an integer key into compressed rows (CSR): the items of key k are
// items[offsets[k] .. offsets[k + 1]), in ascending order of item index. Items with a negative
// key belong to no group. O(#items + #keys), two passes, sequential (deterministic).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace pliant {

// keys_of_items[i]: the key of item i, in [0, num_keys) or negative (left out). offsets gets
// num_keys + 1 entries; items the grouped item indices, each divided by item_divisor (e.g. 3 to
// group triangles by their corners' keys).
inline void group_by_key(std::span<const std::int32_t> keys_of_items, std::size_t num_keys,
                         std::vector<std::int32_t>& offsets, std::vector<std::int32_t>& items,
                         std::int32_t item_divisor = 1) {
    offsets.assign(num_keys + 1, 0);
    for (const std::int32_t key : keys_of_items) {
        if (key >= 0) {
            ++offsets[static_cast<std::size_t>(key) + 1];
        }
    }
    for (std::size_t k = 0; k < num_keys; ++k) {
        offsets[k + 1] += offsets[k];
    }
    items.resize(static_cast<std::size_t>(offsets.back()));
    std::vector<std::int32_t> cursor(offsets.begin(), offsets.end() - 1);
    for (std::size_t i = 0; i < keys_of_items.size(); ++i) {
        const std::int32_t key = keys_of_items[i];
        if (key >= 0) {
            items[static_cast<std::size_t>(cursor[static_cast<std::size_t>(key)]++)] =
                static_cast<std::int32_t>(i) / item_divisor;
        }
    }
}

}  // namespace pliant
