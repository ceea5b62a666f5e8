// Parallel LSD radix sort of 32- or 64-bit keys with a 32-bit payload (stable).
//
// The low key_bits bits are sorted in ceil(key_bits / 11) passes of equal digit width (≤ 11 bits:
// 30-bit Morton codes take 3 passes of 10 bits). Each pass: per fixed-chunk digit histograms →
// offsets (digit-major, chunk-minor) → stable scatter. A pass whose digit is the same for every
// key is skipped. Stable, hence deterministic for 1 and N threads: equal keys keep their input
// order. O(n · passes) time; n keys and payloads of scratch are kept between calls. At most
// 2^32 - 1 elements.
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
    // key_bits: only the low key_bits bits are compared (1..64, 1..32 for 32-bit keys); higher bits
    // must be zero.
    void sort(std::span<std::uint64_t> keys, std::span<std::uint32_t> values, int key_bits = 64);
    void sort(std::span<std::uint32_t> keys, std::span<std::uint32_t> values, int key_bits = 32);

    // Bytes of scratch kept between calls.
    std::size_t memory_bytes() const {
        return m_keys64.capacity() * sizeof(std::uint64_t) +
               (m_keys32.capacity() + m_values.capacity() + m_histograms.capacity()) *
                   sizeof(std::uint32_t);
    }

private:
    template <typename Key>
    void sort_impl(std::span<Key> keys, std::span<std::uint32_t> values, int key_bits,
                   std::vector<Key>& key_scratch);

    std::vector<std::uint64_t> m_keys64;
    std::vector<std::uint32_t> m_keys32;
    std::vector<std::uint32_t> m_values;
    std::vector<std::uint32_t> m_histograms;
};

}  // namespace pliant
