// Creates an output directory (and its parents) for a command's files.
#pragma once

#include <filesystem>

namespace pliant::io {

// Throws IoError "<dir>: cannot create the output directory: <reason>" when dir cannot be
// created or exists as something other than a directory.
void make_output_directory(const std::filesystem::path& dir);

// Throws IoError "<file>: cannot write the output file: a directory of that name is in the way"
// when `file` exists as a directory (or a link to one): checked before a command starts writing,
// so that it does not fail after its other outputs are written.
void require_no_directory_at(const std::filesystem::path& file);

}  // namespace pliant::io
