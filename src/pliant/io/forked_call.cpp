#include "pliant/io/forked_call.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <exception>
#include <new>
#include <optional>
#include <vector>

#include "pliant/core/error.hpp"

// A sanitizer runtime's death callback (sanitizer/common_interface_defs.h), present only when
// one is linked in: libFuzzer sets it to save the current input as a crash.
// clang-format off
// NOLINTNEXTLINE(bugprone-reserved-identifier, cert-dcl37-c, cert-dcl51-cpp, readability-identifier-naming)
extern "C" __attribute__((weak)) void __sanitizer_set_death_callback(void (*callback)());
// clang-format on

namespace pliant::io {
namespace {

// Frame kinds of the record pipe: a record, the end of `work`, or the exception it threw.
constexpr unsigned char FRAME_RECORD = 'R';
constexpr unsigned char FRAME_DONE = 'D';
constexpr unsigned char FRAME_INVALID_INPUT = 'I';
constexpr unsigned char FRAME_IO_ERROR = 'E';
constexpr unsigned char FRAME_UNSUPPORTED = 'U';
constexpr unsigned char FRAME_OTHER = 'X';
constexpr std::size_t FRAME_HEADER = 9;  // kind, then the length as 8 bytes, little endian
constexpr std::size_t STDERR_KEPT = 8192;

// The child's address space now, from /proc/self/statm (0 when unknown).
std::size_t address_space_now() {
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-vararg, hicpp-vararg): POSIX open
    const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        return 0;
    }
    std::array<char, 128> text{};
    const ssize_t got = ::read(fd, text.data(), text.size() - 1);
    ::close(fd);
    std::size_t pages = 0;
    for (ssize_t i = 0; i < got && text[static_cast<std::size_t>(i)] >= '0' &&
                        text[static_cast<std::size_t>(i)] <= '9';
         ++i) {
        pages = pages * 10 + static_cast<std::size_t>(text[static_cast<std::size_t>(i)] - '0');
    }
    return pages * static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
}

[[noreturn]] void child_main(int data_fd, int err_fd, const ForkLimits& limits,
                             FunctionRef<void(ForkChannel&)> work) {
    ::dup2(err_fd, STDERR_FILENO);
    ::close(err_fd);
    sigset_t unblock;
    sigemptyset(&unblock);
    for (const int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGTRAP, SIGPIPE}) {
        struct sigaction action {};
        action.sa_handler = SIG_DFL;  // NOLINT(cppcoreguidelines-pro-type-union-access)
        sigemptyset(&action.sa_mask);
        ::sigaction(sig, &action, nullptr);
        sigaddset(&unblock, sig);
    }
    ::sigprocmask(SIG_UNBLOCK, &unblock, nullptr);
    if (__sanitizer_set_death_callback != nullptr) {
        __sanitizer_set_death_callback(nullptr);
    }
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    if (limits.max_address_space > 0) {
        if (const std::size_t now = address_space_now(); now > 0) {
            const rlimit as{now + limits.max_address_space, now + limits.max_address_space};
            ::setrlimit(RLIMIT_AS, &as);
        }
    }
    ForkChannel channel(data_fd);
    const auto send_error = [&](unsigned char kind, const char* what) {
        channel.send_frame(kind, std::as_bytes(std::span(what, std::strlen(what))));
    };
    try {
        work(channel);
        channel.send_frame(FRAME_DONE, {});
    } catch (const InvalidInput& e) {
        send_error(FRAME_INVALID_INPUT, e.what());
    } catch (const IoError& e) {
        send_error(FRAME_IO_ERROR, e.what());
    } catch (const Unsupported& e) {
        send_error(FRAME_UNSUPPORTED, e.what());
    } catch (const std::bad_alloc&) {
        const std::string what =
            fmt::format("out of memory (it may use {} MiB)", limits.max_address_space >> 20);
        send_error(FRAME_OTHER, what.c_str());
    } catch (const std::exception& e) {
        send_error(FRAME_OTHER, e.what());
    } catch (...) {
        send_error(FRAME_OTHER, "an unknown exception");
    }
    ::_exit(0);
}

std::string signal_name(int sig) {
    switch (sig) {
        case SIGABRT:
            return "SIGABRT";
        case SIGSEGV:
            return "SIGSEGV";
        case SIGBUS:
            return "SIGBUS";
        case SIGFPE:
            return "SIGFPE";
        case SIGILL:
            return "SIGILL";
        case SIGTRAP:
            return "SIGTRAP";
        case SIGKILL:
            return "SIGKILL";
        case SIGPIPE:
            return "SIGPIPE";
        default:
            return fmt::format("signal {}", sig);
    }
}

// The last line of the child's standard error worth quoting (not a sanitizer's "==pid==" line),
// shortened; "" when there is none.
std::string last_line(const std::string& text) {
    std::size_t end = text.size();
    while (end > 0) {
        std::size_t begin = text.rfind('\n', end - 1);
        begin = begin == std::string::npos ? 0 : begin + 1;
        std::string line = text.substr(begin, end - begin);
        while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) {
            line.pop_back();
        }
        if (!line.empty() && !line.starts_with("==")) {
            constexpr std::size_t MAX = 300;
            if (line.size() > MAX) {
                line = line.substr(0, MAX) + "…";
            }
            return line;
        }
        end = begin == 0 ? 0 : begin - 1;
    }
    return {};
}

// Closes the parent's pipe ends and, unless reaped, kills and reaps the child.
struct ChildGuard {
    pid_t pid = -1;
    int data_fd = -1;
    int err_fd = -1;
    bool reaped = false;

    int reap(bool kill_first) {
        if (kill_first) {
            ::kill(pid, SIGKILL);
        }
        int status = 0;
        while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
        reaped = true;
        return status;
    }
    ChildGuard() = default;
    ChildGuard(const ChildGuard&) = delete;
    ChildGuard& operator=(const ChildGuard&) = delete;
    ChildGuard(ChildGuard&&) = delete;
    ChildGuard& operator=(ChildGuard&&) = delete;
    ~ChildGuard() {
        if (data_fd >= 0) {
            ::close(data_fd);
        }
        if (err_fd >= 0) {
            ::close(err_fd);
        }
        if (pid > 0 && !reaped) {
            reap(true);
        }
    }
};

}  // namespace

void ForkChannel::send_frame(unsigned char kind, std::span<const std::byte> bytes) {
    std::array<std::byte, FRAME_HEADER> header{};
    header[0] = static_cast<std::byte>(kind);
    const std::uint64_t length = bytes.size();
    for (std::size_t i = 0; i < 8; ++i) {
        header[1 + i] = static_cast<std::byte>(length >> (8 * i) & 0xFF);
    }
    for (const std::span<const std::byte> part : {std::span<const std::byte>(header), bytes}) {
        std::size_t done = 0;
        while (done < part.size()) {
            const ssize_t n = ::write(m_fd, part.data() + done, part.size() - done);
            if (n < 0 && errno == EINTR) {
                continue;
            }
            if (n <= 0) {
                ::_exit(3);  // the parent is gone or stopped listening
            }
            done += static_cast<std::size_t>(n);
        }
    }
}

void ForkChannel::send(std::span<const std::byte> record) {
    send_frame(FRAME_RECORD, record);
}

ForkedResult run_forked(const ForkLimits& limits, FunctionRef<void(ForkChannel&)> work,
                        FunctionRef<void(std::span<const std::byte>)> on_record) {
    std::array<int, 2> data{-1, -1};
    std::array<int, 2> err{-1, -1};
    if (::pipe2(data.data(), O_CLOEXEC) != 0) {
        throw IoError(
            fmt::format("cannot make a pipe to a child process: {}", std::strerror(errno)));
    }
    if (::pipe2(err.data(), O_CLOEXEC) != 0) {
        const int e = errno;
        ::close(data[0]);
        ::close(data[1]);
        throw IoError(fmt::format("cannot make a pipe to a child process: {}", std::strerror(e)));
    }
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = ::fork();
    if (pid == 0) {
        ::close(data[0]);
        ::close(err[0]);
        child_main(data[1], err[1], limits, work);
    }
    ::close(data[1]);
    ::close(err[1]);
    ChildGuard child;
    child.data_fd = data[0];
    child.err_fd = err[0];
    if (pid < 0) {
        throw IoError(fmt::format("cannot start a child process: {}", std::strerror(errno)));
    }
    child.pid = pid;

    ForkedResult result;
    std::vector<std::byte> pending;  // received, not yet a whole frame
    std::size_t consumed = 0;
    std::string stderr_text;
    std::optional<unsigned char> end_kind;
    std::string end_message;
    const auto quiet = std::chrono::duration<double>(limits.seconds_quiet);
    auto deadline = std::chrono::steady_clock::now() +
                    std::chrono::duration_cast<std::chrono::steady_clock::duration>(quiet);
    bool timed_out = false;
    std::array<std::byte, 65536> chunk{};
    while (child.data_fd >= 0 || child.err_fd >= 0) {
        std::array<pollfd, 2> fds{pollfd{child.data_fd, POLLIN, 0},
                                  pollfd{child.err_fd, POLLIN, 0}};
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) {
            timed_out = true;
            break;
        }
        const int ready = ::poll(fds.data(), fds.size(),
                                 static_cast<int>(std::min<std::int64_t>(left.count(), 1 << 30)));
        if (ready < 0) {
            if (errno == EINTR) {
                continue;
            }
            throw IoError(fmt::format("waiting for a child process: {}", std::strerror(errno)));
        }
        if (fds[1].revents != 0) {
            const ssize_t n = ::read(child.err_fd, chunk.data(), chunk.size());
            if (n > 0) {
                stderr_text.append(reinterpret_cast<const char*>(chunk.data()),
                                   static_cast<std::size_t>(n));
                if (stderr_text.size() > 2 * STDERR_KEPT) {
                    stderr_text.erase(0, stderr_text.size() - STDERR_KEPT);
                }
            } else if (n == 0 || errno != EINTR) {
                ::close(child.err_fd);
                child.err_fd = -1;
            }
        }
        if (fds[0].revents == 0) {
            continue;
        }
        const ssize_t n = ::read(child.data_fd, chunk.data(), chunk.size());
        if (n < 0 && errno == EINTR) {
            continue;
        }
        if (n <= 0) {
            ::close(child.data_fd);
            child.data_fd = -1;
            continue;
        }
        deadline = std::chrono::steady_clock::now() +
                   std::chrono::duration_cast<std::chrono::steady_clock::duration>(quiet);
        pending.insert(pending.end(), chunk.begin(), chunk.begin() + n);
        // Whole frames.
        while (pending.size() - consumed >= FRAME_HEADER) {
            const std::byte* f = pending.data() + consumed;
            std::uint64_t length = 0;
            for (std::size_t i = 0; i < 8; ++i) {
                length |= static_cast<std::uint64_t>(f[1 + i]) << (8 * i);
            }
            if (pending.size() - consumed - FRAME_HEADER < length) {
                break;
            }
            const auto kind = static_cast<unsigned char>(f[0]);
            const std::span<const std::byte> body(f + FRAME_HEADER, length);
            if (kind == FRAME_RECORD) {
                on_record(body);
            } else {
                end_kind = kind;
                end_message.assign(reinterpret_cast<const char*>(body.data()), body.size());
            }
            consumed += FRAME_HEADER + length;
        }
        if (consumed > 0 && consumed == pending.size()) {
            pending.clear();
            consumed = 0;
        }
    }
    const int status = child.reap(timed_out);
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (timed_out) {
        result.failure = fmt::format("sent nothing for {:g} s: killed", limits.seconds_quiet);
        return result;
    }
    if (end_kind) {
        switch (*end_kind) {
            case FRAME_DONE:
                result.completed = true;
                return result;
            case FRAME_INVALID_INPUT:
                throw InvalidInput(end_message);
            case FRAME_IO_ERROR:
                throw IoError(end_message);
            case FRAME_UNSUPPORTED:
                throw Unsupported(end_message);
            default:
                throw IoError(end_message);
        }
    }
    const std::string line = last_line(stderr_text);
    const std::string said = line.empty() ? std::string() : fmt::format(" ({})", line);
    if (WIFSIGNALED(status)) {
        result.failure = fmt::format("killed by {}{}", signal_name(WTERMSIG(status)), said);
    } else {
        result.failure =
            fmt::format("exited with status {} without a result{}", WEXITSTATUS(status), said);
    }
    return result;
}

}  // namespace pliant::io
