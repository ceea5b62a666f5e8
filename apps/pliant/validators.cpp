#include "validators.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <string>

namespace pliant::cli {

const CLI::Validator& finite_non_negative() {
    static const CLI::Validator validator(
        [](std::string& text) -> std::string {
            double value = 0.0;
            const char* end = text.data() + text.size();
            const auto [ptr, ec] = std::from_chars(text.data(), end, value);
            if (ec != std::errc() || ptr != end || !std::isfinite(value) || value < 0.0) {
                return fmt::format("must be a finite number >= 0, got '{}'", text);
            }
            return {};
        },
        "", "FINITE_NON_NEGATIVE");
    return validator;
}

const CLI::Validator& non_empty_path() {
    static const CLI::Validator validator(
        [](std::string& text) -> std::string {
            return text.empty() ? std::string("must be a path, got an empty string")
                                : std::string();
        },
        "", "NON_EMPTY_PATH");
    return validator;
}

}  // namespace pliant::cli
