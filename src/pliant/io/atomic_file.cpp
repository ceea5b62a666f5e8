#include "pliant/io/atomic_file.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>

#include "pliant/core/error.hpp"

namespace pliant::io {

namespace {

std::filesystem::path temporary_path_for(const std::filesystem::path& path) {
    static std::atomic<std::uint64_t> counter{0};
    const std::uint64_t n = counter.fetch_add(1, std::memory_order_relaxed);
    std::filesystem::path tmp = path;
    tmp += fmt::format(".tmp-{}-{}", static_cast<long>(::getpid()), n);
    return tmp;
}

// Removes the temporary file when the write does not reach the final rename.
class TemporaryFile {
public:
    explicit TemporaryFile(std::filesystem::path path) : m_path(std::move(path)) {}
    TemporaryFile(const TemporaryFile&) = delete;
    TemporaryFile& operator=(const TemporaryFile&) = delete;
    ~TemporaryFile() {
        if (m_is_owned) {
            std::error_code ignored;
            std::filesystem::remove(m_path, ignored);
        }
    }
    const std::filesystem::path& path() const { return m_path; }
    void release() { m_is_owned = false; }

private:
    std::filesystem::path m_path;
    bool m_is_owned = true;
};

}  // namespace

void write_file_atomically(const std::filesystem::path& path,
                           FunctionRef<void(std::ostream&)> write) {
    if (!path.has_filename()) {
        throw IoError(fmt::format("{}: cannot write, expected a file name, got a directory path",
                                  path.string()));
    }

    // Step 1: create the temporary next to the target. Ownership is taken before opening so that
    // a file created by a failing open is removed as well.
    TemporaryFile tmp(temporary_path_for(path));
    std::ofstream out(tmp.path(), std::ios::binary | std::ios::trunc);
    if (!out.is_open()) {
        const int error = errno;
        throw IoError(fmt::format("{}: cannot create the temporary file {}: {}", path.string(),
                                  tmp.path().string(), std::strerror(error)));
    }

    // Step 2: the caller's content. Its exceptions propagate; ~TemporaryFile cleans up.
    errno = 0;
    write(out);

    // Step 3: everything must have reached the file before it may replace the target. The
    // stream keeps no error code: errno of the failed write(2) names the cause (ENOSPC for a
    // full disk) when nothing cleared it.
    const auto cause = [] {
        const int error = errno;
        return error != 0 ? fmt::format(": {}", std::strerror(error)) : std::string();
    };
    out.flush();
    if (!out) {
        throw IoError(fmt::format("{}: writing the temporary file {} failed{}", path.string(),
                                  tmp.path().string(), cause()));
    }
    out.close();
    if (out.fail()) {
        throw IoError(fmt::format("{}: closing the temporary file {} failed{}", path.string(),
                                  tmp.path().string(), cause()));
    }

    // Step 4: the atomic replacement.
    std::error_code ec;
    std::filesystem::rename(tmp.path(), path, ec);
    if (ec) {
        throw IoError(fmt::format("{}: cannot replace the file with {}: {}", path.string(),
                                  tmp.path().string(), ec.message()));
    }
    tmp.release();
}

namespace {

// Whether `name` ends with ".tmp-<digits>-<digits>" after at least one character.
bool is_temporary_name(const std::string& name) {
    const std::size_t at = name.rfind(".tmp-");
    if (at == std::string::npos || at == 0) {
        return false;
    }
    const std::string tail = name.substr(at + 5);
    const std::size_t dash = tail.find('-');
    const auto all_digits = [](std::string_view text) {
        return !text.empty() &&
               std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
    };
    return dash != std::string::npos && all_digits(std::string_view(tail).substr(0, dash)) &&
           all_digits(std::string_view(tail).substr(dash + 1));
}

}  // namespace

int remove_stray_temporaries(const std::filesystem::path& dir) {
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        return 0;
    }
    int removed = 0;
    for (const std::filesystem::directory_entry& entry : std::filesystem::directory_iterator(dir)) {
        if (entry.is_regular_file(ec) && is_temporary_name(entry.path().filename().string()) &&
            std::filesystem::remove(entry.path(), ec)) {
            ++removed;
        }
    }
    return removed;
}

}  // namespace pliant::io
