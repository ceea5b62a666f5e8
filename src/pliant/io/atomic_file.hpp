// Atomic file replacement: readers of `path` see either the old content or the complete new
// content, never a partial file.
//
// write_file_atomically(path, write) calls write(stream) on a binary stream to a temporary file in
// the same directory (`<name>.tmp-<pid>-<counter>`, so the final rename stays on one file system),
// flushes and closes it, checks the stream state, then renames it over `path` (replacing a file
// there, or a symbolic link itself rather than its target). On any failure the temporary file is
// removed and `path` is untouched (left absent if it did not exist):
//   - the temporary cannot be created (e.g. the directory does not exist), the stream is in a
//     failed state after `write`, flushing or closing fails, or the rename fails
//     → IoError "<path>: <what failed>";
//   - `write` throws → that exception propagates unchanged.
// Not crash-durable: the data is not fsync'ed, so a power loss may still lose the new content.
// The new file gets default permissions (0666 & ~umask), not those of the file it replaces.
// Thread safe: concurrent calls use distinct temporary names; concurrent writers of the same
// `path` leave one of the complete contents.
#pragma once

#include <filesystem>
#include <ostream>

#include "pliant/core/function_ref.hpp"

namespace pliant::io {

void write_file_atomically(const std::filesystem::path& path,
                           FunctionRef<void(std::ostream&)> write);

// Removes the temporary files write_file_atomically leaves in `dir` (not recursively) when its
// process is killed while writing (`<name>.tmp-<pid>-<counter>`); returns how many. For a run
// that resumes into its own output directory: no other process may be writing there. A missing
// directory holds none.
int remove_stray_temporaries(const std::filesystem::path& dir);

}  // namespace pliant::io
