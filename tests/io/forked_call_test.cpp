#include "pliant/io/forked_call.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "pliant/core/error.hpp"
#include "support/test_files.hpp"

namespace pliant::io {
namespace {

using test::TempDir;

std::string text_of(std::span<const std::byte> bytes) {
    return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

// No child of this process is left unreaped.
void expect_no_child_left() {
    errno = 0;
    EXPECT_EQ(::waitpid(-1, nullptr, WNOHANG), -1);
    EXPECT_EQ(errno, ECHILD);
}

TEST(ForkedCall, RecordsArriveInOrderWholeAndTheRunCompletes) {
    // Sizes around the parent's 64 KiB reads, and one of 5 MB.
    const std::vector<std::size_t> sizes{0, 1, 65535, 65536, 65537, 9, 5u << 20, 3};
    std::vector<std::string> got;
    const ForkedResult run = run_forked(
        {},
        [&](ForkChannel& channel) {
            for (std::size_t n = 0; n < sizes.size(); ++n) {
                channel.send(std::string(sizes[n], static_cast<char>('a' + n)));
            }
        },
        [&](std::span<const std::byte> record) { got.push_back(text_of(record)); });
    EXPECT_TRUE(run.completed) << run.failure;
    EXPECT_EQ(run.failure, "");
    ASSERT_EQ(got.size(), sizes.size());
    for (std::size_t n = 0; n < sizes.size(); ++n) {
        EXPECT_EQ(got[n], std::string(sizes[n], static_cast<char>('a' + n))) << n;
    }
    expect_no_child_left();
}

TEST(ForkedCall, AnAssertionInTheChildIsAFailureWithItsSignalAndMessage) {
    std::vector<std::string> got;
    const ForkedResult run = run_forked(
        {},
        [&](ForkChannel& channel) {
            channel.send(std::string("before"));
            std::fputs("gdcmFake.cxx:12: void f(): Assertion `is.good()' failed.\n", stderr);
            std::abort();
        },
        [&](std::span<const std::byte> record) { got.push_back(text_of(record)); });
    EXPECT_FALSE(run.completed);
    EXPECT_NE(run.failure.find("killed by SIGABRT"), std::string::npos) << run.failure;
    EXPECT_NE(run.failure.find("gdcmFake.cxx:12: void f(): Assertion `is.good()' failed."),
              std::string::npos)
        << run.failure;
    EXPECT_EQ(got, std::vector<std::string>{"before"});
    expect_no_child_left();
}

TEST(ForkedCall, ACrashInTheChildIsAFailure) {
    const ForkedResult run = run_forked(
        {}, [](ForkChannel&) { std::raise(SIGSEGV); }, [](std::span<const std::byte>) {});
    EXPECT_FALSE(run.completed);
    EXPECT_FALSE(run.failure.empty());
    // An exit without a result is one too.
    const ForkedResult exited = run_forked(
        {}, [](ForkChannel&) { ::_exit(7); }, [](std::span<const std::byte>) {});
    EXPECT_FALSE(exited.completed);
    EXPECT_NE(exited.failure.find("exited with status 7 without a result"), std::string::npos)
        << exited.failure;
    expect_no_child_left();
}

// 2 GiB touched would succeed without the limit; with 256 MiB it fails at once, as std::bad_alloc
// (sent back as an IoError) or, under AddressSanitizer, as its out-of-memory report.
TEST(ForkedCall, TheAddressSpaceLimitStopsAHugeAllocation) {
    ForkLimits limits;
    limits.max_address_space = std::size_t{256} << 20;
    bool refused = false;
    try {
        const ForkedResult run = run_forked(
            limits,
            [](ForkChannel& channel) {
                std::vector<char> big(std::size_t{2} << 30, 'x');
                channel.send(std::string(1, big[12345]));
            },
            [](std::span<const std::byte>) {});
        refused = !run.completed;
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("out of memory (it may use 256 MiB)"),
                  std::string::npos)
            << e.what();
        refused = true;
    }
    EXPECT_TRUE(refused);
    // What fits in the limit runs.
    const ForkedResult small = run_forked(
        limits, [](ForkChannel&) { std::vector<char> v(std::size_t{16} << 20, 'x'); },
        [](std::span<const std::byte>) {});
    EXPECT_TRUE(small.completed) << small.failure;
    expect_no_child_left();
}

TEST(ForkedCall, AChildThatSendsNothingIsKilledAfterTheTimeLimit) {
    ForkLimits limits;
    limits.seconds_quiet = 0.3;
    int records = 0;
    const ForkedResult run = run_forked(
        limits,
        [](ForkChannel& channel) {
            channel.send(std::string("one"));
            std::this_thread::sleep_for(std::chrono::seconds(60));
        },
        [&](std::span<const std::byte>) { ++records; });
    EXPECT_FALSE(run.completed);
    EXPECT_EQ(run.failure, "sent nothing for 0.3 s: killed");
    EXPECT_EQ(records, 1);
    expect_no_child_left();
}

template <typename E>
void expect_rethrown(auto&& thrower, const std::string& message) {
    try {
        run_forked({}, thrower, [](std::span<const std::byte>) {});
        ADD_FAILURE() << "expected an exception: " << message;
    } catch (const E& e) {
        EXPECT_EQ(std::string(e.what()), message);
    } catch (const std::exception& e) {
        ADD_FAILURE() << "wrong exception type: " << e.what();
    }
}

TEST(ForkedCall, ExceptionsInTheChildAreThrownAgainWithTheirTypeAndMessage) {
    expect_rethrown<InvalidInput>([](ForkChannel&) { throw InvalidInput("a.dcm: bad"); },
                                  "a.dcm: bad");
    expect_rethrown<IoError>([](ForkChannel&) { throw IoError("b.dcm: unreadable"); },
                             "b.dcm: unreadable");
    expect_rethrown<Unsupported>([](ForkChannel&) { throw Unsupported("c.dcm: colour"); },
                                 "c.dcm: colour");
    expect_rethrown<IoError>([](ForkChannel&) { throw std::runtime_error("other"); }, "other");
    expect_no_child_left();
}

TEST(ForkedCall, AnExceptionFromOnRecordKillsAndReapsTheChild) {
    int records = 0;
    try {
        run_forked(
            {},
            [](ForkChannel& channel) {
                for (;;) {
                    channel.send(std::string(1000, 'r'));
                }
            },
            [&](std::span<const std::byte>) {
                if (++records == 3) {
                    throw InvalidInput("enough");
                }
            });
        ADD_FAILURE() << "expected InvalidInput";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), "enough");
    }
    EXPECT_EQ(records, 3);
    expect_no_child_left();
}

// The child ends with _exit: the caller's unflushed stdio buffers are not written twice.
TEST(ForkedCall, TheChildDoesNotFlushTheCallersBuffers) {
    TempDir dir;
    const auto path = dir / "out.txt";
    std::FILE* f = std::fopen(path.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("once", f);  // buffered, not yet written
    const ForkedResult run = run_forked(
        {}, [](ForkChannel&) {}, [](std::span<const std::byte>) {});
    EXPECT_TRUE(run.completed) << run.failure;
    std::fclose(f);
    EXPECT_EQ(test::read_bytes(path), "once");
}

}  // namespace
}  // namespace pliant::io
