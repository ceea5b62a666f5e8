// Running code that parses untrusted input through a third-party library (GDCM) in a forked child
// process, so that the library's assertions, crashes, runaway allocations and hangs end the
// child, not the caller.
//
// run_forked(limits, work, on_record): fork()s; the child runs work(channel), which sends
// records (byte strings) to the parent through a pipe; the parent calls on_record for each, in
// order, as they arrive. The child's standard error goes to a pipe too: its last line is kept for
// the failure message (a glibc assertion prints one). Inside the child:
//   - SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGTRAP have their default action (a handler
//     the caller installed, such as libFuzzer's, must not run there), no core file is written,
//     and a sanitizer's death callback is cleared (libFuzzer's would save the input as a crash);
//   - RLIMIT_AS allows limits.max_address_space bytes beyond the address space the child starts
//     with (what it inherits, sanitizer shadow included), so an absurd allocation fails at once;
//   - it ends with _exit: no atexit handlers, static destructors, stdio flushes or leak checks.
// An exception thrown by `work` is sent to the parent and thrown there again: InvalidInput,
// IoError and Unsupported with their type and message, anything else as IoError.
// The parent kills the child (SIGKILL) when it sends no record for limits.seconds_quiet.
//
// Returns whether the child ran `work` to its end; when it did not (a signal, an exit without a
// result, the time limit, a pipe error), `failure` says why in words ("killed by signal SIGABRT
// (gdcmFoo.cxx:12: … Assertion `x' failed.)", "sent nothing for 60 s: killed"). The records
// received before that were passed to on_record. An exception thrown by on_record kills and reaps
// the child, then propagates. Throws IoError when the pipes or the fork cannot be made.
//
// Costs a fork (about 1 ms for a process of 100 MB; the page tables are copied, not the pages).
// Not async-signal-safe work in the child is the price: the child of a multi-threaded process
// runs `work` while locks another thread held at the fork may stay taken. glibc's malloc and
// stdio are reset in the child; `work` must not use the caller's own locks (a stuck child is
// killed by the time limit).
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>

#include "pliant/core/function_ref.hpp"

namespace pliant::io {

struct ForkLimits {
    std::size_t max_address_space = std::size_t{1} << 30;  // bytes beyond the inherited; 0: none
    double seconds_quiet = 60.0;  // the longest the child may go without sending a record
};

// The child's end of the record pipe.
class ForkChannel {
public:
    explicit ForkChannel(int fd) : m_fd(fd) {}
    // Sends one record (blocking while the pipe is full).
    void send(std::span<const std::byte> record);
    void send(std::string_view record) {
        send(std::as_bytes(std::span(record.data(), record.size())));
    }
    // Internal: a frame of the protocol (kind byte, 64-bit length, bytes).
    void send_frame(unsigned char kind, std::span<const std::byte> bytes);

private:
    int m_fd;
};

struct ForkedResult {
    bool completed = false;  // work returned (or threw, which run_forked rethrows)
    std::string failure;     // when !completed: why, in words
    double seconds = 0.0;    // wall time from the fork to reaping the child
};

ForkedResult run_forked(const ForkLimits& limits, FunctionRef<void(ForkChannel&)> work,
                        FunctionRef<void(std::span<const std::byte>)> on_record);

}  // namespace pliant::io
