// Parallel LSD radix sort of 64-bit keys with a 32-bit payload (8-bit digits, stable).
//
// Each pass: per fixed-chunk digit histograms → offsets (digit-major, chunk-minor) → stable
// scatter. Passes whose digit is the same for every key are skipped, so sorting keys below 2^30
// costs at most 4 passes. Stable, hence deterministic for 1 and N threads: equal keys keep their
// input order. O(n · passes) time, n extra keys and payloads of scratch kept between calls.
//
// Not thread safe: one RadixSorter per concurrent caller.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace pliant {

class RadixSorter {
public:
    // Sorts keys ascending and permutes values alongside. keys.size() == values.size() (checked).
    // key_bits: only the low key_bits bits are compared (1..64); higher bits must be zero.
    void sort(std::span<std::uint64_t> keys, std::span<std::uint32_t> values, int key_bits = 64);

private:
    std::vector<std::uint64_t> m_keys;
    std::vector<std::uint32_t> m_values;
    std::vector<std::uint32_t> m_histograms;
};

}  // namespace pliant
