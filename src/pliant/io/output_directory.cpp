#include "pliant/io/output_directory.hpp"

#include <fmt/format.h>

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

}  // namespace pliant::io
