#include "output_directory.hpp"

#include <fmt/format.h>

#include <system_error>

#include "pliant/core/error.hpp"

namespace pliant::cli {

void make_output_directory(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec || !std::filesystem::is_directory(dir)) {
        throw IoError(fmt::format("{}: cannot create the output directory: {}", dir.string(),
                                  ec ? ec.message() : "not a directory"));
    }
}

}  // namespace pliant::cli
