// Runs the pliant command-line tool (PLIANT_CLI, the built binary) for end-to-end tests.
//
// run_cli("collide a.ply --json") runs `PLIANT_CLI collide a.ply --json` through the shell with
// stdout and stderr redirected to files in a scratch directory, and returns the exit code (-1
// when the process did not exit normally) and both streams. Arguments are passed to the shell as
// written: quote paths with quoted(). ScratchDir is a fresh directory per test, removed at the end.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace pliant::test {

struct CliResult {
    int exit_code = -1;
    std::string out;
    std::string err;
};

class ScratchDir {
public:
    ScratchDir() {
        const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
        const std::string name = info != nullptr
                                     ? std::string(info->test_suite_name()) + "." + info->name()
                                     : std::string("no_test");
        m_path = std::filesystem::temp_directory_path() /
                 ("pliant_cli_" + name + "_" + std::to_string(::getpid()));
        std::filesystem::remove_all(m_path);
        std::filesystem::create_directories(m_path);
    }
    ScratchDir(const ScratchDir&) = delete;
    ScratchDir& operator=(const ScratchDir&) = delete;
    ~ScratchDir() {
        std::error_code ignored;
        std::filesystem::remove_all(m_path, ignored);
    }
    const std::filesystem::path& path() const { return m_path; }
    std::filesystem::path operator/(const std::string& name) const { return m_path / name; }

private:
    std::filesystem::path m_path;
};

// The path in single quotes for the shell (test paths contain no single quote).
inline std::string quoted(const std::filesystem::path& path) {
    std::string text(1, '\'');
    text.append(path.string());
    text.push_back('\'');
    return text;
}

// The whole file ("" when it cannot be opened). stdio rather than iostreams: GCC 12's
// -Wnull-dereference misfires on istreambuf_iterator.
inline std::string read_text(const std::filesystem::path& path) {
    std::string text;
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (file == nullptr) {
        return text;
    }
    char buffer[4096];
    std::size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, file)) > 0) {
        text.append(buffer, n);
    }
    std::fclose(file);
    return text;
}

// environment: shell variable assignments put before the command (e.g. "PATH=/nonexistent").
inline CliResult run_cli(const std::string& args, const ScratchDir& scratch,
                         const std::string& environment = "") {
    const std::filesystem::path out = scratch / "stdout.txt";
    const std::filesystem::path err = scratch / "stderr.txt";
    const std::string command = environment + " " + quoted(PLIANT_CLI) + " " + args + " >" +
                                quoted(out) + " 2>" + quoted(err);
    const int status = std::system(command.c_str());
    CliResult result;
    result.exit_code = status != -1 && WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = read_text(out);
    result.err = read_text(err);
    return result;
}

}  // namespace pliant::test
