#include "pliant/pipeline/frame_pipeline.hpp"

#include <exception>

#include "pliant/core/error.hpp"
#include "pliant/core/parallel_task.hpp"

namespace pliant::pipeline {

void run_frame_pipeline(int first, int last, FunctionRef<void(int frame, int slot)> produce,
                        FunctionRef<void(int frame, int slot)> consume,
                        const FramePipelineOptions& options) {
    if (options.producer_threads < 0) {
        throw InvalidInput("run_frame_pipeline: producer_threads must be >= 0");
    }
    const auto slot = [](int frame) {
        return frame & 1;
    };
    if (!options.pipelined) {
        for (int f = first; f <= last; ++f) {
            produce(f, slot(f));
            consume(f, slot(f));
        }
        return;
    }
    if (last < first) {
        return;
    }
    BackgroundTask next(options.producer_threads);
    produce(first, slot(first));
    for (int f = first; f <= last; ++f) {
        if (f < last) {
            next.start([&produce, f, &slot] { produce(f + 1, slot(f + 1)); });
        }
        try {
            consume(f, slot(f));
        } catch (...) {
            const std::exception_ptr error = std::current_exception();
            try {
                next.wait();  // the work in flight writes the other slot: let it end first
            } catch (...) {
                // The consume's exception is the one reported.
            }
            std::rethrow_exception(error);
        }
        next.wait();
    }
}

}  // namespace pliant::pipeline
