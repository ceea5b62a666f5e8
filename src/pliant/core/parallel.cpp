#include "pliant/core/parallel.hpp"

#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/info.h>
#include <oneapi/tbb/parallel_for.h>

#include <atomic>
#include <memory>
#include <mutex>

#include "pliant/core/error.hpp"

namespace pliant {
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
    const int limit = thread_limit().limit.load();
    if (limit > 0) {
        return limit;
    }
    return static_cast<int>(
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
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
    tbb::parallel_for(
        tbb::blocked_range<std::int64_t>(0, count, 1),
        [&](const tbb::blocked_range<std::int64_t>& range) {
            for (std::int64_t c = range.begin(); c < range.end(); ++c) {
                body(c);
            }
        },
        tbb::auto_partitioner{});
}

}  // namespace detail
}  // namespace pliant
