// Text helpers shared by the text-format readers (OBJ, PLY, NRRD, MetaImage, DICOM):
// locale-independent number parsing of a whole token (std::from_chars), quoting of file content
// for error messages, and the small string operations of header parsing.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pliant::io::detail {

enum class ParseStatus { ok, not_a_number, out_of_range };

// Parses the whole token as a decimal real ("1", "-2.5e-3", "+7", "nan", "inf"). Values that
// underflow the type become the nearest representable value (possibly ±0); values that overflow
// it give out_of_range. Anything else than one number, with no surrounding spaces, gives
// not_a_number. `out` is written only on ok.
ParseStatus parse_real(std::string_view token, float& out);
ParseStatus parse_real(std::string_view token, double& out);

// Parses the whole token as a decimal integer with optional sign.
ParseStatus parse_integer(std::string_view token, std::int64_t& out);

// `text` in single quotes for an error message: at most 40 characters (then "..."), bytes that
// are not printable ASCII as \xNN.
std::string quote(std::string_view text);

// `text` without leading and trailing white space (std::isspace).
std::string trim(std::string_view text);
// ASCII letters of `text` in lower case.
std::string lower(std::string text);
// The white-space separated words of `text`.
std::vector<std::string> words(std::string_view text);

// A space or a tab: what separates the tokens of an OBJ line.
inline bool is_blank(char c) {
    return c == ' ' || c == '\t';
}
// The tokens of `text` split on spaces and tabs (as tinyobjloader does) into `tokens`, which is
// cleared first; views into `text`.
void split_blank_tokens(std::string_view text, std::vector<std::string_view>& tokens);

}  // namespace pliant::io::detail
