#include "validators.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <string>

namespace pliant::cli {

namespace {

// Whether text is a whole decimal number (std::from_chars: no hex, no spaces) that is finite.
bool finite_number(const std::string& text, double& value) {
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    return ec == std::errc() && ptr == end && std::isfinite(value);
}

}  // namespace

const CLI::Validator& finite_non_negative() {
    static const CLI::Validator VALIDATOR(
        [](std::string& text) -> std::string {
            double value = 0.0;
            if (!finite_number(text, value) || value < 0.0) {
                return fmt::format("must be a finite number >= 0, got '{}'", text);
            }
            return {};
        },
        "", "FINITE_NON_NEGATIVE");
    return VALIDATOR;
}

CLI::Validator finite_in_range(double lo, double hi) {
    return {[lo, hi](std::string& text) -> std::string {
                double value = 0.0;
                if (!finite_number(text, value) || value < lo || value > hi) {
                    return fmt::format("must be a finite number in [{}, {}], got '{}'", lo, hi,
                                       text);
                }
                return {};
            },
            "", "FINITE_IN_RANGE"};
}

const CLI::Validator& non_empty_path() {
    static const CLI::Validator VALIDATOR(
        [](std::string& text) -> std::string {
            return text.empty() ? std::string("must be a path, got an empty string")
                                : std::string();
        },
        "", "NON_EMPTY_PATH");
    return VALIDATOR;
}

CLI::Option* add_max_memory_option(CLI::App& cmd, double& mib, const std::string& what) {
    return cmd
        .add_option("--max-memory", mib,
                    "Refuse " + what +
                        " more memory than this, MiB, before allocating (default: the memory "
                        "available: physical, or the control group's limit)")
        ->type_name("MIB")
        ->check(finite_in_range(1e-6, 1e12));
}

}  // namespace pliant::cli
