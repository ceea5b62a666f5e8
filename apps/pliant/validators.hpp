// CLI11 validators shared by the commands.
#pragma once

#include <CLI/CLI.hpp>

namespace pliant::cli {

// A finite number >= 0. CLI11's NonNegativeNumber lets NaN through; this one does not.
const CLI::Validator& finite_non_negative();
// A finite decimal number in [lo, hi] (CLI::Range lets NaN through, and CLI11 reads 0x10 as 16).
CLI::Validator finite_in_range(double lo, double hi);
// A non-empty path: an empty --out or -o would write into the current directory.
const CLI::Validator& non_empty_path();

}  // namespace pliant::cli
