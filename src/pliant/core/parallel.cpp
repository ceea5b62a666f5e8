#include "pliant/core/parallel.hpp"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant {
namespace detail {
// The concurrency of the BackgroundTask whose work this thread runs (0: none; parallel_task.cpp).
thread_local int t_concurrency_cap = 0;
}  // namespace detail

namespace {

struct ThreadLimit {
    std::mutex mutex;
    std::unique_ptr<tbb::global_control> control;
    std::atomic<int> limit{0};
};

ThreadLimit& thread_limit() {
    static ThreadLimit state;
    return state;
}

}  // namespace

int hardware_threads() {
    return tbb::info::default_concurrency();
}

void set_num_threads(int n) {
    if (n < 0) {
        throw InvalidInput("set_num_threads: n (" + std::to_string(n) + ") must be >= 0");
    }
    ThreadLimit& state = thread_limit();
    std::lock_guard lock(state.mutex);
    state.control.reset();
    const int effective = n == 0 ? hardware_threads() : n;
    state.control = std::make_unique<tbb::global_control>(
        tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(effective));
    state.limit.store(effective);
}

int num_threads() {
    int limit = thread_limit().limit.load();
    if (limit <= 0) {
        limit = static_cast<int>(
            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
    }
    const int cap = detail::t_concurrency_cap;
    return cap > 0 ? std::max(1, std::min(limit, cap)) : limit;
}

namespace detail {

void run_chunks(std::int64_t count, FunctionRef<void(std::int64_t)> body) {
    if (count <= 0) {
        return;
    }
    if (count == 1 || num_threads() == 1) {
        for (std::int64_t c = 0; c < count; ++c) {
            body(c);
        }
        return;
    }
#if defined(PLIANT_PARALLEL_STD_THREADS)
    // The ThreadSanitizer build (PLIANT_SANITIZE=thread): ThreadSanitizer cannot see the
    // synchronization inside Debian's uninstrumented libtbb and reports its work stealing as
    // races, so the same fixed chunks run on std::threads taking chunks from an atomic counter.
    // What it checks is unchanged: the chunking and every body's memory accesses.
    std::atomic<std::int64_t> next{0};
    const auto work = [&] {
        for (std::int64_t c = next.fetch_add(1); c < count; c = next.fetch_add(1)) {
            body(c);
        }
    };
    const auto workers = static_cast<std::int64_t>(num_threads()) < count
                             ? static_cast<std::int64_t>(num_threads())
                             : count;
    std::vector<std::thread> threads;
    for (std::int64_t t = 1; t < workers; ++t) {
        threads.emplace_back(work);
    }
    work();
    for (std::thread& thread : threads) {
        thread.join();
    }
#else
    tbb::parallel_for(
        tbb::blocked_range<std::int64_t>(0, count, 1),
        [&](const tbb::blocked_range<std::int64_t>& range) {
            for (std::int64_t c = range.begin(); c < range.end(); ++c) {
                body(c);
            }
        },
        tbb::auto_partitioner{});
#endif
}

}  // namespace detail
}  // namespace pliant
