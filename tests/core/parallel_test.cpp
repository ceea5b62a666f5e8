#include "pliant/core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <numeric>
#include <random>

#include "pliant/core/chunked_buffer.hpp"
#include "pliant/core/scan.hpp"

namespace pliant {
namespace {

// Restores the process-wide thread limit after a test.
class ParallelTest : public ::testing::Test {
protected:
    void TearDown() override { set_num_threads(0); }
};

TEST_F(ParallelTest, ForVisitsEveryIndexOnce) {
    for (const std::int64_t n : {0, 1, 7, 4096, 4097, 100000}) {
        std::vector<std::atomic<int>> hits(static_cast<std::size_t>(n));
        parallel_for(
            n, [&](std::int64_t i) { hits[static_cast<std::size_t>(i)]++; }, 1000);
        for (std::int64_t i = 0; i < n; ++i) {
            ASSERT_EQ(hits[static_cast<std::size_t>(i)].load(), 1) << "n=" << n << " i=" << i;
        }
    }
}

TEST_F(ParallelTest, ChunksAreFixedByGrain) {
    std::vector<std::pair<std::int64_t, std::int64_t>> chunks(3);
    parallel_for_chunks(25, 10, [&](std::int64_t c, std::int64_t b, std::int64_t e) {
        chunks[static_cast<std::size_t>(c)] = {b, e};
    });
    EXPECT_EQ(chunks[0], std::make_pair(std::int64_t{0}, std::int64_t{10}));
    EXPECT_EQ(chunks[1], std::make_pair(std::int64_t{10}, std::int64_t{20}));
    EXPECT_EQ(chunks[2], std::make_pair(std::int64_t{20}, std::int64_t{25}));
    EXPECT_EQ(num_chunks(0, 10), 0);
    EXPECT_EQ(num_chunks(10, 10), 1);
}

// A float sum depends on association order; fixed chunks make it independent of the threads.
TEST_F(ParallelTest, FloatReduceIsBitwiseIdenticalForOneAndManyThreads) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1e3f, 1e3f);
    std::vector<float> values(1 << 20);
    for (float& v : values) {
        v = u(rng);
    }
    const auto sum = [&] {
        return parallel_reduce(
            static_cast<std::int64_t>(values.size()), 0.0f,
            [&](std::int64_t b, std::int64_t e) {
                float s = 0.0f;
                for (std::int64_t i = b; i < e; ++i) {
                    s += values[static_cast<std::size_t>(i)];
                }
                return s;
            },
            [](float a, float b) { return a + b; }, 1000);
    };
    set_num_threads(1);
    const float one = sum();
    set_num_threads(4);
    EXPECT_EQ(num_threads(), 4);
    const float many = sum();
    EXPECT_EQ(std::memcmp(&one, &many, sizeof(float)), 0);
    // And it is a sum: compare with a double-precision reference.
    const double reference = std::accumulate(values.begin(), values.end(), 0.0);
    EXPECT_NEAR(one, reference, 1.0);
}

TEST_F(ParallelTest, ExclusiveScanMatchesSequentialAndWorksInPlace) {
    for (const std::size_t n :
         {std::size_t{0}, std::size_t{1}, std::size_t{5}, std::size_t{100000}}) {
        std::vector<std::uint32_t> in(n);
        std::mt19937 rng(static_cast<std::uint32_t>(n));
        for (auto& v : in) {
            v = rng() % 100;
        }
        std::vector<std::uint32_t> expected(n);
        std::exclusive_scan(in.begin(), in.end(), expected.begin(), 0u);
        const std::uint32_t expected_total = std::accumulate(in.begin(), in.end(), 0u);
        std::vector<std::uint32_t> out(n);
        EXPECT_EQ(exclusive_scan(std::span<const std::uint32_t>(in), std::span(out), 1000),
                  expected_total);
        EXPECT_EQ(out, expected);
        EXPECT_EQ(exclusive_scan(std::span(in), 999), expected_total);  // in place
        EXPECT_EQ(in, expected);
    }
}

TEST_F(ParallelTest, ChunkedBufferGathersInChunkOrderForAnyThreadCount) {
    const auto run = [](int threads) {
        set_num_threads(threads);
        ChunkedBuffer<int> buffer;
        buffer.reset(num_chunks(10000, 64));
        parallel_for_chunks(10000, 64, [&](std::int64_t c, std::int64_t b, std::int64_t e) {
            for (std::int64_t i = b; i < e; ++i) {
                if (i % 3 == 0) {
                    buffer.chunk(c).push_back(static_cast<int>(i));
                }
            }
        });
        std::vector<int> out;
        buffer.gather(out);
        return out;
    };
    const std::vector<int> one = run(1);
    EXPECT_EQ(one, run(2));
    EXPECT_EQ(one, run(4));
    ASSERT_EQ(one.size(), 3334u);
    EXPECT_TRUE(std::is_sorted(one.begin(), one.end()));
}

TEST_F(ParallelTest, ThreadLimitIsRespectedAndValidated) {
    set_num_threads(1);
    EXPECT_EQ(num_threads(), 1);
    EXPECT_THROW(set_num_threads(-1), InvalidInput);
    set_num_threads(0);
    EXPECT_EQ(num_threads(), hardware_threads());
}

}  // namespace
}  // namespace pliant
