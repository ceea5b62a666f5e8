#include "pliant/core/parallel_task.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

namespace pliant {
namespace {

class BackgroundTaskTest : public ::testing::Test {
protected:
    void TearDown() override { set_num_threads(0); }
};

// Whether `flag` was set within 10 seconds (yielding while it is not).
bool wait_for(const std::atomic<bool>& flag) {
    const auto limit = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!flag.load() && std::chrono::steady_clock::now() < limit) {
        std::this_thread::yield();
    }
    return flag.load();
}

// n values of 1000 sin(i), and their sum by a chunked parallel reduction (grain 1000), whose
// bits depend on the chunks only.
template <typename T>
std::vector<T> sine_values(std::size_t n) {
    std::vector<T> values(n);
    for (std::size_t i = 0; i < n; ++i) {
        values[i] = std::sin(static_cast<T>(i)) * T{1000};
    }
    return values;
}

template <typename T>
T chunked_sum(const std::vector<T>& values) {
    return parallel_reduce(
        static_cast<std::int64_t>(values.size()), T{0},
        [&](std::int64_t b, std::int64_t e) {
            T s{0};
            for (std::int64_t i = b; i < e; ++i) {
                s += values[static_cast<std::size_t>(i)];
            }
            return s;
        },
        [](T a, T b) { return a + b; }, 1000);
}

// The work runs while the caller goes on: it waits for a flag only the caller sets after
// start() returned (a work run inside start() would give up after its time limit), and it runs
// without the caller waiting for it (a work run only inside wait() would never set `running`).
TEST_F(BackgroundTaskTest, RunsConcurrentlyWithTheCaller) {
    set_num_threads(2);
    std::atomic<bool> go{false};
    std::atomic<bool> running{false};
    std::atomic<bool> saw_go{false};
    BackgroundTask task;
    task.start([&] {
        running = true;
        saw_go = wait_for(go);
    });
    EXPECT_TRUE(task.is_started());
    EXPECT_TRUE(wait_for(running));
    EXPECT_FALSE(task.is_done());
    go = true;
    task.wait();
    EXPECT_TRUE(saw_go.load());
    EXPECT_TRUE(task.is_done());
    EXPECT_FALSE(task.is_started());
}

TEST_F(BackgroundTaskTest, OneThreadRunsTheWorkInStart) {
    set_num_threads(1);
    BackgroundTask task;
    int value = 0;
    task.start([&] { value = 42; });
    EXPECT_TRUE(task.is_done());
    EXPECT_EQ(value, 42);
    task.wait();
}

// Parallel loops inside the work give the results they give on the caller's thread.
TEST_F(BackgroundTaskTest, ParallelLoopsInsideAreDeterministic) {
    set_num_threads(2);
    const std::vector<float> values = sine_values<float>(200000);
    const auto sum = [&] {
        return chunked_sum(values);
    };
    const float here = sum();
    float there = 0.0f;
    BackgroundTask task;
    for (int round = 0; round < 3; ++round) {
        task.start([&] { there = sum(); });
        task.wait();
        EXPECT_EQ(std::memcmp(&here, &there, sizeof(float)), 0) << "round " << round;
    }
}

// BackgroundTask(1): the work sees one thread (its parallel loops run inline), runs while the
// caller goes on, and the caller's own parallel loops still see the thread limit.
TEST_F(BackgroundTaskTest, ConcurrencyOneRunsTheWorkOnOneThread) {
    set_num_threads(2);
    BackgroundTask task(1);
    std::atomic<bool> go{false};
    std::atomic<bool> running{false};
    std::atomic<bool> saw_go{false};
    int inside = 0;
    bool inline_loop = true;
    task.start([&] {
        inside = num_threads();
        const std::thread::id me = std::this_thread::get_id();
        parallel_for(
            64,
            [&](std::int64_t) { inline_loop = inline_loop && std::this_thread::get_id() == me; },
            1);
        running = true;
        saw_go = wait_for(go);
    });
    EXPECT_EQ(num_threads(), 2);
    EXPECT_TRUE(wait_for(running));
    EXPECT_FALSE(task.is_done());
    go = true;
    task.wait();
    EXPECT_TRUE(saw_go.load());
    EXPECT_EQ(inside, 1);
    EXPECT_TRUE(inline_loop);
    // Reusable, and the default concurrency still sees the limit.
    task.start([&] { inside = num_threads(); });
    task.wait();
    EXPECT_EQ(inside, 1);
    BackgroundTask all;
    all.start([&] { inside = num_threads(); });
    all.wait();
    EXPECT_EQ(inside, 2);
    EXPECT_THROW(BackgroundTask(-1), InvalidInput);
}

// A one-thread work's parallel reductions give the bits of the caller's.
TEST_F(BackgroundTaskTest, ConcurrencyOneIsDeterministic) {
    set_num_threads(2);
    const std::vector<double> values = sine_values<double>(100000);
    const auto sum = [&] {
        return chunked_sum(values);
    };
    BackgroundTask task(1);
    double there = 0.0;
    task.start([&] { there = sum(); });
    const double here = sum();  // concurrently, on the caller's threads
    task.wait();
    EXPECT_EQ(std::memcmp(&here, &there, sizeof(double)), 0);
}

TEST_F(BackgroundTaskTest, ExceptionsAndMisuse) {
    set_num_threads(2);
    BackgroundTask task;
    task.wait();  // nothing started: no-op
    task.start([] { throw InvalidInput("bad frame"); });
    EXPECT_THROW(task.start([] {}), InvalidInput);  // the previous work was not waited for
    try {
        task.wait();
        FAIL() << "no rethrow";
    } catch (const InvalidInput& e) {
        EXPECT_STREQ(e.what(), "bad frame");
    }
    // Usable again; the destructor waits for unfinished work.
    std::atomic<int> runs{0};
    {
        BackgroundTask scoped;
        scoped.start([&] {
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
            ++runs;
        });
    }
    EXPECT_EQ(runs.load(), 1);
    task.start([&] { ++runs; });
    task.wait();
    EXPECT_EQ(runs.load(), 2);
}

}  // namespace
}  // namespace pliant
