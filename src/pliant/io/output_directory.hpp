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

// Throws IoError "<file>: cannot write the output file: cannot create a file in <dir>: <reason>"
// when write_file_atomically(file, …) could not even start: its directory is missing, read-only
// or not writable for this process (require_no_directory_at's case too). Creates and removes an
// empty `<file>.tmp-<pid>-probe` beside it, the test the writer itself makes; called by long runs
// (deform, nerf train) before they start, so that they do not fail after the work is done.
void require_writable_file(const std::filesystem::path& file);

}  // namespace pliant::io
