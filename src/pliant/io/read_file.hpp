// Reads a whole file into memory with one bulk read. Throws IoError "<path>: <reason>" when the
// file is missing, is not a regular file, or cannot be read completely.
#pragma once

#include <filesystem>
#include <string>

namespace pliant::io {

std::string read_file(const std::filesystem::path& path);

}  // namespace pliant::io
