// Option values the commands parse alike: image sizes and file extensions.
#pragma once

#include <array>
#include <string>

namespace pliant::cli {

// "WxH" → {W, H}, each in [1, 16384]; CLI::ValidationError naming `option` (exit 2) otherwise.
std::array<int, 2> parse_size(const std::string& text, const std::string& option = "--size");

// True when `path` ends in `ext` (".png"; case-insensitive).
bool has_extension(const std::string& path, const char* ext);

}  // namespace pliant::cli
