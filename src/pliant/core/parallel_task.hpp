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
// to completion before it returns.
//
// Concurrency: by default the work may use every thread of the limit (the caller helps only
// inside wait()). BackgroundTask(1) runs the work on one thread: num_threads() answers 1 inside
// it, so its parallel loops run inline, on their one-thread paths, and never wait for a second
// thread; the other threads stay free for the caller's parallel loops (the frame pipeline,
// pipeline/frame_pipeline.hpp: the soft body steps on one thread while the last frame renders on
// the rest, and the stepping thread joins the render when its work ends). With concurrency
// k > 1 the work's parallel loops use at most k threads. With a concurrency k ≥ 1 start()
// returns once the work runs on its thread, so the caller's parallel loops that follow cannot
// take that thread from it (they overlap the work instead of delaying it). Results of the work are
// unaffected by where it runs (fixed chunks, core/parallel.hpp). One task at a time per object;
// start, wait and is_done are called from one thread; the destructor waits.
#pragma once

#include <functional>
#include <memory>

namespace pliant {

class BackgroundTask {
public:
    BackgroundTask();
    // concurrency ≥ 1: the most threads the work uses; 0: the thread limit (the default).
    explicit BackgroundTask(int concurrency);
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
