#include "pliant/io/child_process.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <thread>

#include "pliant/core/error.hpp"

extern char** environ;  // NOLINT: POSIX, passed to the child process

namespace pliant::io {
namespace {

bool is_executable_file(const std::filesystem::path& p) {
    struct stat st {};
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
}

// Waits for the child, killing it first when `kill_first` (SIGTERM, SIGKILL after 2 s).
int reap(pid_t pid, bool kill_first) {
    int status = 0;
    if (kill_first) {
        ::kill(pid, SIGTERM);
        for (int i = 0; i < 40; ++i) {
            const pid_t r = ::waitpid(pid, &status, WNOHANG);
            if (r == pid || (r < 0 && errno != EINTR)) {
                return status;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
        ::kill(pid, SIGKILL);
    }
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
}

}  // namespace

std::filesystem::path find_program(const std::string& name) {
    const char* env = std::getenv("PATH");
    const std::string_view path_list = env != nullptr ? env : "/usr/local/bin:/usr/bin:/bin";
    std::size_t start = 0;
    while (start <= path_list.size()) {
        std::size_t end = path_list.find(':', start);
        if (end == std::string_view::npos) {
            end = path_list.size();
        }
        const std::string_view dir = path_list.substr(start, end - start);
        if (!dir.empty()) {
            std::filesystem::path candidate = std::filesystem::path(dir) / name;
            if (is_executable_file(candidate)) {
                return candidate;
            }
        }
        start = end + 1;
    }
    return {};
}

ChildProcessResult run_child_process(const std::vector<std::string>& argv,
                                     const std::filesystem::path& log, FunctionRef<bool()> poll) {
    if (argv.empty()) {
        throw InvalidInput("run_child_process: empty argument vector");
    }
    std::filesystem::path program = argv[0];
    if (argv[0].find('/') == std::string::npos) {
        program = find_program(argv[0]);
        if (program.empty()) {
            throw IoError(fmt::format("{}: not found on $PATH", argv[0]));
        }
    }
    ChildProcessResult result;
    if (!poll()) {
        result.stopped = true;
        return result;
    }
    // NOLINTNEXTLINE(cppcoreguidelines-pro-type-vararg, hicpp-vararg): POSIX open
    const int log_fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (log_fd < 0) {
        throw IoError(fmt::format("{}: cannot open the log {}: {}", argv[0], log.string(),
                                  std::strerror(errno)));
    }
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const std::string& a : argv) {
        args.push_back(const_cast<char*>(a.c_str()));
    }
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_adddup2(&actions, log_fd, STDOUT_FILENO);
    posix_spawn_file_actions_adddup2(&actions, log_fd, STDERR_FILENO);
    posix_spawnattr_t attributes;
    posix_spawnattr_init(&attributes);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETPGROUP);
    posix_spawnattr_setpgroup(&attributes, 0);
    const auto start = std::chrono::steady_clock::now();
    pid_t pid = -1;
    const int spawn_error =
        ::posix_spawn(&pid, program.c_str(), &actions, &attributes, args.data(), environ);
    posix_spawnattr_destroy(&attributes);
    posix_spawn_file_actions_destroy(&actions);
    ::close(log_fd);
    if (spawn_error != 0) {
        throw IoError(fmt::format("{}: cannot start {}: {}", argv[0], program.string(),
                                  std::strerror(spawn_error)));
    }

    int status = 0;
    try {
        for (;;) {
            const pid_t r = ::waitpid(pid, &status, WNOHANG);
            if (r == pid) {
                break;
            }
            if (r < 0 && errno != EINTR) {
                throw IoError(fmt::format("{}: waitpid failed: {}", argv[0], std::strerror(errno)));
            }
            if (!poll()) {
                reap(pid, true);
                result.stopped = true;
                break;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
        }
    } catch (...) {
        reap(pid, true);
        throw;
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!result.stopped) {
        if (WIFSIGNALED(status)) {
            result.signaled = true;
            result.signal = WTERMSIG(status);
        } else {
            result.exit_code = WEXITSTATUS(status);
        }
    }
    return result;
}

}  // namespace pliant::io
