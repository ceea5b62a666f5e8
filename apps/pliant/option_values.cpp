#include "option_values.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

namespace pliant::cli {

std::array<int, 2> parse_size(const std::string& text, const std::string& option) {
    int w = 0, h = 0;
    char x = 0, extra = 0;
    if (std::sscanf(text.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || x != 'x' || w < 1 ||
        h < 1 || w > 16384 || h > 16384) {
        throw CLI::ValidationError(
            option, fmt::format("expected WxH with 1 <= W, H <= 16384, got '{}'", text));
    }
    return {w, h};
}

bool has_extension(const std::string& path, const char* ext) {
    std::string e = std::filesystem::path(path).extension().string();
    std::transform(e.begin(), e.end(), e.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return e == ext;
}

}  // namespace pliant::cli
