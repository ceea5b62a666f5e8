// CLI11 validators shared by the commands.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace pliant::cli {

// A finite number >= 0. CLI11's NonNegativeNumber lets NaN through; this one does not.
const CLI::Validator& finite_non_negative();
// A finite decimal number in [lo, hi] (CLI::Range lets NaN through, and CLI11 reads 0x10 as 16).
CLI::Validator finite_in_range(double lo, double hi);
// A non-empty path: an empty --out or -o would write into the current directory.
const CLI::Validator& non_empty_path();

// --max-memory MIB (finite, in [1e-6, 1e12]) into `mib`: "Refuse <what> that need(s) more memory
// than this, MiB, before allocating (default: the memory available …)". The command checks its
// need against it with pipeline/memory_budget.hpp before it allocates.
CLI::Option* add_max_memory_option(CLI::App& cmd, double& mib, const std::string& what);

}  // namespace pliant::cli
