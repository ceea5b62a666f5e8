// Wording shared by the JSON readers (cloth scenes, transfer functions): what a JSON value is,
// for "expected X, got Y" messages.
#pragma once

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <string>

namespace pliant::io {

// "an integer", "a number", or "a JSON <type>" (string, array, object, boolean, null).
inline std::string json_type_name(const nlohmann::json& value) {
    if (value.is_number_integer() || value.is_number_unsigned()) {
        return "an integer";
    }
    if (value.is_number()) {
        return "a number";
    }
    return fmt::format("a JSON {}", value.type_name());
}

}  // namespace pliant::io
