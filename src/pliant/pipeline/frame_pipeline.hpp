// A frame loop whose consecutive frames overlap: frame f + 1 is made (the soft body's step and
// its inverse map or resampled volume) on a background thread while frame f is used (rendered,
// written) on the caller's threads — the throughput of `pliant deform --render` (issue 29).
//
//   run_frame_pipeline(1, frames, produce, consume, {});
//   produce(f, slot): makes frame f into buffer slot (0 or 1), e.g. body.step(dt);
//   build_map(maps[slot]) consume(f, slot): uses frame f from that slot, e.g. set_map(maps[slot]);
//   render; write
//
// Order (pipelined): produce(first) on the caller, then for every frame f: produce(f + 1) in a
// BackgroundTask ‖ consume(f) on the caller, then wait. So produce(f) runs after produce(f − 1)
// and after consume(f − 2) (the last user of its slot, slot = f mod 2), and consume(f) after
// produce(f) and consume(f − 1): two buffers suffice, and a produce that only reads what the
// previous produce wrote and a consume that only reads its slot give the sequential loop's
// results bit for bit (with deterministic stages, core/parallel.hpp). Sequential (pipelined =
// false): produce(f), consume(f) for every f, the same slots.
//
// Threads: the background work runs with concurrency producer_threads (core/parallel_task.hpp:
// 1 means its parallel loops run inline, e.g. the soft body's one-thread sweep, which never
// spins waiting for a second thread); the caller's parallel loops use the other threads and,
// once the work ends, the thread it ran on (oneTBB's work stealing). With a thread limit of 1
// the background work runs inside start(): the pipelined order on one thread.
//
// An exception from produce or consume ends the loop after the work in flight has ended, and is
// rethrown (the first one: a consume's before the produce it overlapped).
#pragma once

#include "pliant/core/function_ref.hpp"

namespace pliant::pipeline {

struct FramePipelineOptions {
    bool pipelined = true;
    // The background work's concurrency: ≥ 1, or 0 for the thread limit (BackgroundTask's
    // default: the work's loops may use every thread, the step its two lanes).
    int producer_threads = 1;
};

// Frames first..last (none when last < first).
void run_frame_pipeline(int first, int last, FunctionRef<void(int frame, int slot)> produce,
                        FunctionRef<void(int frame, int slot)> consume,
                        const FramePipelineOptions& options);

}  // namespace pliant::pipeline
