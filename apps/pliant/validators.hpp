// CLI11 validators shared by the commands.
#pragma once

#include <CLI/CLI.hpp>

namespace pliant::cli {

// A finite number >= 0. CLI11's NonNegativeNumber lets NaN through; this one does not.
const CLI::Validator& finite_non_negative();
// A non-empty path: an empty --out or -o would write into the current directory.
const CLI::Validator& non_empty_path();

}  // namespace pliant::cli
