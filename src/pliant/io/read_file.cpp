#include "pliant/io/read_file.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <system_error>

#include "pliant/core/error.hpp"

namespace pliant::io {

namespace {

struct FileCloser {
    void operator()(std::FILE* file) const { std::fclose(file); }
};

}  // namespace

std::string read_file(const std::filesystem::path& path) {
    std::error_code ec;
    const std::filesystem::file_status status = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(status)) {
        throw IoError(fmt::format("{}: cannot open file, expected an existing file, got {}",
                                  path.string(), ec ? ec.message() : "no such file"));
    }
    if (!std::filesystem::is_regular_file(status)) {
        throw IoError(
            fmt::format("{}: cannot read, expected a regular file, got a {}", path.string(),
                        std::filesystem::is_directory(status) ? "directory" : "special file"));
    }

    // std::FILE keeps this a single fread of the whole size, with errno for the message.
    const std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
    if (!file) {
        throw IoError(fmt::format("{}: cannot open file: {}", path.string(), std::strerror(errno)));
    }
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) {
        throw IoError(fmt::format("{}: cannot get the file size: {}", path.string(), ec.message()));
    }
    std::string bytes(static_cast<std::size_t>(size), '\0');
    const std::size_t num_read = std::fread(bytes.data(), 1, bytes.size(), file.get());
    if (num_read != bytes.size() || std::ferror(file.get()) != 0) {
        throw IoError(fmt::format("{}: read error, expected {} bytes, got {}", path.string(),
                                  bytes.size(), num_read));
    }
    return bytes;
}

}  // namespace pliant::io
