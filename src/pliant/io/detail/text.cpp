#include "pliant/io/detail/text.hpp"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

namespace pliant::io::detail {

namespace {

// from_chars rejects a leading '+', which C, OBJ and PLY writers may emit.
std::string_view strip_plus(std::string_view token) {
    if (token.size() >= 2 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
        token.remove_prefix(1);
    }
    return token;
}

template <typename Real>
ParseStatus parse_real_impl(std::string_view token, Real& out) {
    token = strip_plus(token);
    Real value{};
    const char* end = token.data() + token.size();
    const std::from_chars_result result = std::from_chars(token.data(), end, value);
    if (result.ptr != end || token.empty()) {
        return ParseStatus::not_a_number;
    }
    if (result.ec == std::errc::result_out_of_range) {
        // from_chars reports underflow and overflow alike and leaves `value` unset. strtod tells
        // them apart (±HUGE_VAL only on overflow); this path is rare, so the copy is cheap.
        const std::string copy(token);
        const Real fallback = [&] {
            if constexpr (std::is_same_v<Real, float>) {
                return std::strtof(copy.c_str(), nullptr);
            } else {
                return std::strtod(copy.c_str(), nullptr);
            }
        }();
        if (std::isinf(fallback)) {
            return ParseStatus::out_of_range;
        }
        value = fallback;
    } else if (result.ec != std::errc{}) {
        return ParseStatus::not_a_number;
    }
    out = value;
    return ParseStatus::ok;
}

}  // namespace

ParseStatus parse_real(std::string_view token, float& out) {
    return parse_real_impl(token, out);
}

ParseStatus parse_real(std::string_view token, double& out) {
    return parse_real_impl(token, out);
}

ParseStatus parse_integer(std::string_view token, std::int64_t& out) {
    token = strip_plus(token);
    std::int64_t value = 0;
    const char* end = token.data() + token.size();
    const std::from_chars_result result = std::from_chars(token.data(), end, value);
    if (result.ptr != end || token.empty()) {
        return ParseStatus::not_a_number;
    }
    if (result.ec == std::errc::result_out_of_range) {
        return ParseStatus::out_of_range;
    }
    if (result.ec != std::errc{}) {
        return ParseStatus::not_a_number;
    }
    out = value;
    return ParseStatus::ok;
}

std::string quote(std::string_view text) {
    constexpr std::size_t MAX_CHARS = 40;
    std::string out = "'";
    for (std::size_t i = 0; i < text.size() && i < MAX_CHARS; ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (c >= 0x20 && c < 0x7f) {
            out.push_back(static_cast<char>(c));
        } else {
            out += fmt::format("\\x{:02x}", c);
        }
    }
    if (text.size() > MAX_CHARS) {
        out += "...";
    }
    out.push_back('\'');
    return out;
}

std::string trim(std::string_view text) {
    std::size_t b = 0;
    std::size_t e = text.size();
    while (b < e && std::isspace(static_cast<unsigned char>(text[b])) != 0) {
        ++b;
    }
    while (e > b && std::isspace(static_cast<unsigned char>(text[e - 1])) != 0) {
        --e;
    }
    return std::string(text.substr(b, e - b));
}

std::string lower(std::string text) {
    for (char& c : text) {
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return text;
}

std::vector<std::string> words(std::string_view text) {
    std::vector<std::string> out;
    std::istringstream in{std::string(text)};
    std::string w;
    while (in >> w) {
        out.push_back(w);
    }
    return out;
}

void split_blank_tokens(std::string_view text, std::vector<std::string_view>& tokens) {
    tokens.clear();
    std::size_t i = 0;
    while (i < text.size()) {
        while (i < text.size() && is_blank(text[i])) {
            ++i;
        }
        const std::size_t start = i;
        while (i < text.size() && !is_blank(text[i])) {
            ++i;
        }
        if (i > start) {
            tokens.push_back(text.substr(start, i - start));
        }
    }
}

}  // namespace pliant::io::detail
