#include "pliant/core/radix_sort.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant {
namespace {

// Reference: std::stable_sort of (key, value) by key.
void reference_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values) {
    std::vector<std::size_t> order(keys.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
    std::vector<std::uint64_t> k(keys.size());
    std::vector<std::uint32_t> v(values.size());
    for (std::size_t i = 0; i < order.size(); ++i) {
        k[i] = keys[order[i]];
        v[i] = values[order[i]];
    }
    keys.swap(k);
    values.swap(v);
}

struct Case {
    std::size_t n;
    int key_bits;
    std::uint64_t modulus;  // keys drawn in [0, modulus): small moduli force many equal keys
};

// How gtest (and so ctest's test names) print a case.
void PrintTo(const Case& c, std::ostream* os) {
    *os << "n=" << c.n << " key_bits=" << c.key_bits << " modulus=" << c.modulus;
}

class RadixSortTest : public ::testing::TestWithParam<Case> {
protected:
    void TearDown() override { set_num_threads(0); }
};

TEST_P(RadixSortTest, MatchesStableSortForOneAndManyThreads) {
    const Case c = GetParam();
    std::mt19937_64 rng(c.n * 31 + static_cast<std::uint64_t>(c.key_bits));
    std::vector<std::uint64_t> keys(c.n);
    std::vector<std::uint32_t> values(c.n);
    for (std::size_t i = 0; i < c.n; ++i) {
        keys[i] = rng() % c.modulus;
        values[i] = static_cast<std::uint32_t>(i);
    }
    auto expected_keys = keys;
    auto expected_values = values;
    reference_sort(expected_keys, expected_values);
    for (const int threads : {1, 3}) {
        set_num_threads(threads);
        auto k = keys;
        auto v = values;
        RadixSorter sorter;
        sorter.sort(k, v, c.key_bits);
        EXPECT_EQ(k, expected_keys) << "threads=" << threads;
        EXPECT_EQ(v, expected_values) << "threads=" << threads;
    }
}

INSTANTIATE_TEST_SUITE_P(Sizes, RadixSortTest,
                         ::testing::Values(Case{0, 64, 1}, Case{1, 64, 10}, Case{2, 64, 2},
                                           Case{1000, 30, 1u << 30}, Case{200000, 30, 1u << 30},
                                           Case{200000, 30, 7}, Case{150000, 64, ~0ull},
                                           Case{70000, 64, 1}),
                         // Readable, stable names (the default prints the struct's bytes,
                         // padding included).
                         [](const ::testing::TestParamInfo<Case>& param_info) {
                             return fmt::format("n{}_bits{}_case{}", param_info.param.n,
                                                param_info.param.key_bits, param_info.index);
                         });

TEST(RadixSort, ThirtyTwoBitKeysMatchStableSort) {
    for (const int key_bits : {30, 32, 7}) {
        std::mt19937 rng(static_cast<std::uint32_t>(key_bits));
        const std::size_t n = 150000;
        std::vector<std::uint32_t> keys32(n), values(n);
        std::vector<std::uint64_t> keys64(n);
        for (std::size_t i = 0; i < n; ++i) {
            keys32[i] = key_bits == 32 ? rng() : rng() & ((1u << key_bits) - 1);
            keys64[i] = keys32[i];
            values[i] = static_cast<std::uint32_t>(i);
        }
        auto expected_values = values;
        reference_sort(keys64, expected_values);
        auto v = values;
        RadixSorter sorter;
        sorter.sort(std::span(keys32), std::span(v), key_bits);
        EXPECT_EQ(std::vector<std::uint64_t>(keys32.begin(), keys32.end()), keys64) << key_bits;
        EXPECT_EQ(v, expected_values) << key_bits;
    }
    std::vector<std::uint32_t> k(4), v(4);
    RadixSorter sorter;
    EXPECT_THROW(sorter.sort(std::span(k), std::span(v), 33), InvalidInput);
}

TEST(RadixSort, RejectsMismatchedSpans) {
    std::vector<std::uint64_t> keys(3);
    std::vector<std::uint32_t> values(2);
    RadixSorter sorter;
    EXPECT_THROW(sorter.sort(keys, values), InvalidInput);
    std::vector<std::uint32_t> values3(3);
    EXPECT_THROW(sorter.sort(keys, values3, 0), InvalidInput);
    EXPECT_THROW(sorter.sort(keys, values3, 65), InvalidInput);
}

}  // namespace
}  // namespace pliant
