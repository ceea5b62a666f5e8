// Ctrl-C for the long commands: while an InterruptGuard lives, SIGINT does not end the process
// but sets a flag that the pipeline run polls (its keep-going callback), so the run stops after
// the unit of work in progress with its outputs consistent.
#pragma once

#include <signal.h>  // NOLINT(modernize-deprecated-headers): sigaction is POSIX, not <csignal>

namespace pliant::cli {

// Installs the handler for its lifetime and restores the previous one. Not nestable.
class InterruptGuard {
public:
    InterruptGuard();
    ~InterruptGuard();
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    // False once SIGINT arrived: what a pipeline::KeepGoingFn returns.
    static bool keep_going();

private:
    struct sigaction m_previous {};
};

}  // namespace pliant::cli
