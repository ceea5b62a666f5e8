// CLI11 validators shared by the commands.
#pragma once

#include <CLI/CLI.hpp>

namespace pliant::cli {

// A finite number >= 0. CLI11's NonNegativeNumber lets NaN through; this one does not.
const CLI::Validator& finite_non_negative();

}  // namespace pliant::cli
