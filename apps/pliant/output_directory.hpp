// Creates an output directory (and its parents) for a command's files.
#pragma once

#include <filesystem>

namespace pliant::cli {

// Throws IoError "<dir>: cannot create the output directory: <reason>" when dir cannot be
// created or exists as something other than a directory.
void make_output_directory(const std::filesystem::path& dir);

}  // namespace pliant::cli
