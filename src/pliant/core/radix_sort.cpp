#include "pliant/core/radix_sort.hpp"

#include <algorithm>
#include <array>

#include "pliant/core/check.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant {
namespace {

constexpr int DIGIT_BITS = 8;
constexpr std::uint32_t BUCKETS = 1u << DIGIT_BITS;
constexpr std::int64_t SORT_GRAIN = 1 << 16;

}  // namespace

void RadixSorter::sort(std::span<std::uint64_t> keys, std::span<std::uint32_t> values,
                       int key_bits) {
    if (keys.size() != values.size()) {
        throw InvalidInput(fmt::format("RadixSorter::sort: keys.size() ({}) != values.size() ({})",
                                       keys.size(), values.size()));
    }
    if (key_bits < 1 || key_bits > 64) {
        throw InvalidInput(fmt::format("RadixSorter::sort: key_bits ({}) not in [1, 64]", key_bits));
    }
    const auto n = static_cast<std::int64_t>(keys.size());
    if (n <= 1) {
        return;
    }
    const std::int64_t chunks = num_chunks(n, SORT_GRAIN);
    m_keys.resize(keys.size());
    m_values.resize(values.size());
    m_histograms.resize(static_cast<std::size_t>(chunks) * BUCKETS);

    std::span<std::uint64_t> src_keys = keys;
    std::span<std::uint32_t> src_values = values;
    std::span<std::uint64_t> dst_keys = m_keys;
    std::span<std::uint32_t> dst_values = m_values;

    for (int shift = 0; shift < key_bits; shift += DIGIT_BITS) {
        // Step 1: per-chunk histograms of this digit.
        parallel_for_chunks(n, SORT_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
            std::uint32_t* histogram = m_histograms.data() + c * BUCKETS;
            std::fill(histogram, histogram + BUCKETS, 0u);
            for (std::int64_t i = begin; i < end; ++i) {
                ++histogram[(src_keys[static_cast<std::size_t>(i)] >> shift) & (BUCKETS - 1)];
            }
        });
        // Step 2: skip the pass when one bucket holds every key; else turn counts into offsets,
        // digit-major then chunk-minor, which keeps the scatter stable.
        std::array<std::uint64_t, BUCKETS> totals{};
        for (std::int64_t c = 0; c < chunks; ++c) {
            for (std::uint32_t b = 0; b < BUCKETS; ++b) {
                totals[b] += m_histograms[static_cast<std::size_t>(c) * BUCKETS + b];
            }
        }
        if (std::any_of(totals.begin(), totals.end(),
                        [n](std::uint64_t t) { return t == static_cast<std::uint64_t>(n); })) {
            continue;
        }
        std::uint32_t offset = 0;
        for (std::uint32_t b = 0; b < BUCKETS; ++b) {
            for (std::int64_t c = 0; c < chunks; ++c) {
                std::uint32_t& h = m_histograms[static_cast<std::size_t>(c) * BUCKETS + b];
                const std::uint32_t count = h;
                h = offset;
                offset += count;
            }
        }
        // Step 3: stable scatter.
        parallel_for_chunks(n, SORT_GRAIN, [&](std::int64_t c, std::int64_t begin, std::int64_t end) {
            std::uint32_t* cursor = m_histograms.data() + c * BUCKETS;
            for (std::int64_t i = begin; i < end; ++i) {
                const std::uint64_t key = src_keys[static_cast<std::size_t>(i)];
                const std::uint32_t at = cursor[(key >> shift) & (BUCKETS - 1)]++;
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

}  // namespace pliant
