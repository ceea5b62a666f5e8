// JSON text shared by the JSON readers (raw-volume sidecars, cloth scenes, transfer functions,
// NeRF datasets, CCD ground truth): parsing with one error, and the wording of "expected X, got
// Y" messages.
#pragma once

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <string>
#include <string_view>

#include "pliant/core/error.hpp"

namespace pliant::io {

// Parses text as one JSON document. Throws IoError "<name>: not valid JSON: <why>" for any
// text nlohmann::json refuses: a syntax error (parse_error) and a number too large for a double
// or integer, e.g. 1e999 (out_of_range 406).
inline nlohmann::json parse_json(std::string_view text, std::string_view name) {
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception& e) {
        throw IoError(fmt::format("{}: not valid JSON: {}", name, e.what()));
    }
}

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
