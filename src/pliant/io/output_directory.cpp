#include "pliant/io/output_directory.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

#include "pliant/core/error.hpp"

namespace pliant::io {

void make_output_directory(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir)) {
        throw IoError(fmt::format("{}: cannot create the output directory: {}", dir.string(),
                                  ec ? ec.message() : "not a directory"));
    }
}

void require_no_directory_at(const std::filesystem::path& file) {
    std::error_code ec;
    if (std::filesystem::is_directory(file, ec)) {
        throw IoError(
            fmt::format("{}: cannot write the output file: a directory of that name is in the way",
                        file.string()));
    }
}

void require_writable_file(const std::filesystem::path& file) {
    require_no_directory_at(file);
    const std::filesystem::path dir =
        file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
    std::filesystem::path probe = file;
    probe += fmt::format(".tmp-{}-probe", static_cast<long>(::getpid()));
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) {
        const int error = errno;
        throw IoError(
            fmt::format("{}: cannot write the output file: cannot create a file in {}: {}",
                        file.string(), dir.string(), std::strerror(error)));
    }
    ::close(fd);
    ::unlink(probe.c_str());
}

}  // namespace pliant::io
