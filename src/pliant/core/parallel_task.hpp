// BackgroundTask: one piece of work run concurrently with the calling thread — the interactive
// viewer simulates the next frame while it draws the last one. Part of the parallel layer (the
// only place that talks to a threading library): the work runs in a oneTBB arena of its own on
// the worker threads, so a caller that draws is never pulled into a simulation chunk; wait()
// joins the arena and helps with the work's parallel loops (core/parallel.hpp) until it ends.
//
//   BackgroundTask task;
//   task.start([&] { solver.step(dt, substeps); });   // returns at once
//   while (!task.is_done()) { draw(previous_state); }
//   task.wait();                                       // rethrows what the work threw
//
// With a thread limit of 1 (set_num_threads(1)) there is no second thread: start() runs the work
// to completion before it returns. Results of the work are unaffected by where it runs (fixed
// chunks, core/parallel.hpp). One task at a time per object; start, wait and is_done are called
// from one thread; the destructor waits.
#pragma once

#include <functional>
#include <memory>

namespace pliant {

class BackgroundTask {
public:
    BackgroundTask();
    ~BackgroundTask();
    BackgroundTask(const BackgroundTask&) = delete;
    BackgroundTask& operator=(const BackgroundTask&) = delete;

    // Starts `work` (InvalidInput when a previous work has not been waited for).
    void start(std::function<void()> work);
    // True when no work was started since the last wait(), or the started work has finished.
    bool is_done() const;
    // True between start() and the matching wait().
    bool is_started() const;
    // Blocks until the work has finished, then rethrows the exception it threw, if any. No-op
    // without started work.
    void wait();

private:
    struct State;
    std::unique_ptr<State> m_state;
};

}  // namespace pliant
