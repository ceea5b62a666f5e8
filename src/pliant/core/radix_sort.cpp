#include "pliant/core/radix_sort.hpp"

#include <algorithm>
#include <limits>

#include "pliant/core/check.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant {
namespace {

constexpr int MAX_DIGIT_BITS = 11;
constexpr std::int64_t SORT_GRAIN = 1 << 16;

}  // namespace

void RadixSorter::sort(std::span<std::uint64_t> keys, std::span<std::uint32_t> values,
                       int key_bits) {
    sort_impl(keys, values, key_bits, m_keys64);
}

void RadixSorter::sort(std::span<std::uint32_t> keys, std::span<std::uint32_t> values,
                       int key_bits) {
    sort_impl(keys, values, key_bits, m_keys32);
}

template <typename Key>
void RadixSorter::sort_impl(std::span<Key> keys, std::span<std::uint32_t> values, int key_bits,
                            std::vector<Key>& key_scratch) {
    constexpr int KEY_BITS = 8 * sizeof(Key);
    if (keys.size() != values.size()) {
        throw InvalidInput(fmt::format("RadixSorter::sort: keys.size() ({}) != values.size() ({})",
                                       keys.size(), values.size()));
    }
    if (key_bits < 1 || key_bits > KEY_BITS) {
        throw InvalidInput(
            fmt::format("RadixSorter::sort: key_bits ({}) not in [1, {}]", key_bits, KEY_BITS));
    }
    if (keys.size() > std::numeric_limits<std::uint32_t>::max()) {
        throw InvalidInput(fmt::format("RadixSorter::sort: {} keys, at most {} supported",
                                       keys.size(), std::numeric_limits<std::uint32_t>::max()));
    }
    const auto n = static_cast<std::int64_t>(keys.size());
    if (n <= 1) {
        return;
    }
    const int passes = (key_bits + MAX_DIGIT_BITS - 1) / MAX_DIGIT_BITS;
    const int digit_bits = (key_bits + passes - 1) / passes;
    const std::uint32_t buckets = 1u << digit_bits;
    const Key digit_mask = static_cast<Key>(buckets - 1);
    const std::int64_t chunks = num_chunks(n, SORT_GRAIN);
    key_scratch.resize(keys.size());
    m_values.resize(values.size());
    m_histograms.resize(static_cast<std::size_t>(chunks) * buckets);

    std::span<Key> src_keys = keys;
    std::span<std::uint32_t> src_values = values;
    std::span<Key> dst_keys = key_scratch;
    std::span<std::uint32_t> dst_values = m_values;

    for (int shift = 0; shift < key_bits; shift += digit_bits) {
        // Step 1: per-chunk histograms of this digit.
        parallel_for_chunks(
            n, SORT_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                std::uint32_t* histogram = m_histograms.data() + c * buckets;
                std::fill(histogram, histogram + buckets, 0u);
                for (std::int64_t i = begin; i < end; ++i) {
                    ++histogram[(src_keys[static_cast<std::size_t>(i)] >> shift) & digit_mask];
                }
            });
        // Step 2: skip the pass when one bucket holds every key; else turn counts into offsets,
        // digit-major then chunk-minor, which keeps the scatter stable.
        bool trivial = false;
        std::uint32_t offset = 0;
        for (std::uint32_t b = 0; b < buckets && !trivial; ++b) {
            const std::uint32_t start = offset;
            for (std::int64_t c = 0; c < chunks; ++c) {
                std::uint32_t& h = m_histograms[static_cast<std::size_t>(c) * buckets + b];
                const std::uint32_t count = h;
                h = offset;
                offset += count;
            }
            trivial = offset - start == static_cast<std::uint32_t>(n);
        }
        if (trivial) {
            continue;
        }
        // Step 3: stable scatter.
        parallel_for_chunks(n, SORT_GRAIN,
                            [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
                                std::uint32_t* cursor = m_histograms.data() + c * buckets;
                                for (std::int64_t i = begin; i < end; ++i) {
                                    const Key key = src_keys[static_cast<std::size_t>(i)];
                                    const std::uint32_t at = cursor[(key >> shift) & digit_mask]++;
                                    dst_keys[at] = key;
                                    dst_values[at] = src_values[static_cast<std::size_t>(i)];
                                }
                            });
        std::swap(src_keys, dst_keys);
        std::swap(src_values, dst_values);
    }
    if (src_keys.data() != keys.data()) {
        std::copy(src_keys.begin(), src_keys.end(), keys.begin());
        std::copy(src_values.begin(), src_values.end(), values.begin());
    }
}

template void RadixSorter::sort_impl(std::span<std::uint64_t>, std::span<std::uint32_t>, int,
                                     std::vector<std::uint64_t>&);
template void RadixSorter::sort_impl(std::span<std::uint32_t>, std::span<std::uint32_t>, int,
                                     std::vector<std::uint32_t>&);

}  // namespace pliant
