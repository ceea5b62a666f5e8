#include "pliant/core/parallel_task.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"

#if !defined(PLIANT_PARALLEL_STD_THREADS)
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>
#endif

namespace pliant {

namespace detail {
extern thread_local int t_concurrency_cap;  // parallel.cpp
}  // namespace detail

struct BackgroundTask::State {
    int concurrency = 0;  // 0: the thread limit
    std::mutex mutex;
    std::condition_variable finished;
    std::atomic<bool> done{true};
    std::atomic<bool> begun{false};  // the work started on its thread
    bool started = false;
    std::exception_ptr error;
#if defined(PLIANT_PARALLEL_STD_THREADS)
    // The ThreadSanitizer build: a plain thread (parallel.cpp explains why).
    std::thread thread;
#else
    // An arena of its own: the work and its parallel loops run on its workers, and a caller
    // that waits joins it and helps (its reserved slot); outside wait() the caller never
    // executes the work's chunks, nor the work the caller's.
    std::unique_ptr<tbb::task_arena> arena;
    tbb::task_group group;
#endif
};

BackgroundTask::BackgroundTask() : m_state(std::make_unique<State>()) {}

BackgroundTask::BackgroundTask(int concurrency) : m_state(std::make_unique<State>()) {
    if (concurrency < 0) {
        throw InvalidInput("BackgroundTask: concurrency (" + std::to_string(concurrency) +
                           ") must be >= 0");
    }
    m_state->concurrency = concurrency;
}

BackgroundTask::~BackgroundTask() {
    try {
        wait();
    } catch (...) {
        // The work's exception is dropped when nobody waited for it.
    }
}

void BackgroundTask::start(std::function<void()> work) {
    State& s = *m_state;
    if (s.started) {
        throw InvalidInput("BackgroundTask::start: the previous work was not waited for");
    }
    s.started = true;
    s.error = nullptr;
    s.done.store(false);
    s.begun.store(false);
    auto run = [&s, work = std::move(work)] {
        s.begun.store(true, std::memory_order_release);
        // The work's thread answers num_threads() with the task's concurrency.
        const int outer_cap = detail::t_concurrency_cap;
        detail::t_concurrency_cap = s.concurrency;
        try {
            work();
        } catch (...) {
            s.error = std::current_exception();
        }
        detail::t_concurrency_cap = outer_cap;
        {
            const std::lock_guard lock(s.mutex);
            s.done.store(true);
        }
        s.finished.notify_all();
    };
    if (num_threads() == 1) {
        run();  // no second thread allowed
        return;
    }
#if defined(PLIANT_PARALLEL_STD_THREADS)
    s.thread = std::thread(std::move(run));
#else
    const int threads = num_threads();
    const int concurrency = s.concurrency > 0 ? std::min(s.concurrency, threads) : threads;
    if (!s.arena || s.arena->max_concurrency() != concurrency) {
        // All threads: a slot kept for the caller, who helps inside wait(). Fewer: every slot
        // for workers, the caller's wait() only blocks (it would add a thread).
        s.arena = std::make_unique<tbb::task_arena>(concurrency, s.concurrency > 0 ? 0 : 1);
    }
    s.arena->execute([&s, &run] { s.group.run(std::move(run)); });
    if (s.concurrency > 0) {
        // No slot for the caller: only a worker runs the work, and oneTBB gives an idle worker
        // to whichever arena asks first. Were the caller's next parallel loops to take it, the
        // work would wait for them to end instead of overlapping them: return once it runs (the
        // workers are idle here, so this waits for a wake-up only).
        while (!s.begun.load(std::memory_order_acquire) && !s.done.load()) {
            std::this_thread::yield();
        }
    }
#endif
}

bool BackgroundTask::is_done() const {
    return m_state->done.load();
}

bool BackgroundTask::is_started() const {
    return m_state->started;
}

void BackgroundTask::wait() {
    State& s = *m_state;
    if (!s.started) {
        return;
    }
#if defined(PLIANT_PARALLEL_STD_THREADS)
    {
        std::unique_lock lock(s.mutex);
        s.finished.wait(lock, [&s] { return s.done.load(); });
    }
    if (s.thread.joinable()) {
        s.thread.join();
    }
#else
    if (s.arena) {
        if (s.concurrency > 0) {
            // No slot for the caller: block until the work has ended, then join the group.
            std::unique_lock lock(s.mutex);
            s.finished.wait(lock, [&s] { return s.done.load(); });
        }
        s.arena->execute([&s] { s.group.wait(); });  // helps with the work's parallel loops
    }
#endif
    s.started = false;
    if (s.error) {
        std::exception_ptr error = std::exchange(s.error, nullptr);
        std::rethrow_exception(error);
    }
}

}  // namespace pliant
