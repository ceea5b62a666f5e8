// The PLY header: its grammar, scalar types and the element/property layout it declares.
//
//   ply
//   format <ascii|binary_little_endian|binary_big_endian> 1.0
//   comment … | obj_info …                                    (ignored, anywhere)
//   element <name> <count>
//   property <type> <name>                                    (a scalar)
//   property list <count type> <item type> <name>             (a list; count type is an integer)
//   end_header
//
// Lines end with \n or \r\n. The data section starts right after the end_header line.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pliant/io/ply.hpp"

namespace pliant::io::detail {

enum class PlyScalar : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

// Bytes of one binary value: 1, 2, 4 or 8.
std::size_t size_of(PlyScalar type);
bool is_integer(PlyScalar type);
// The traditional name: char uchar short ushort int uint float double.
const char* to_string(PlyScalar type);
// Accepts both the traditional names and int8 … float64.
std::optional<PlyScalar> parse_scalar_type(std::string_view name);

struct PlyProperty {
    std::string name;
    PlyScalar type = PlyScalar::float32;  // a list's item type
    bool is_list = false;
    PlyScalar count_type = PlyScalar::uint8;  // lists only; always an integer type
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
    std::size_t line = 0;  // the header line that declares the element

    // Index into `properties`, if a property has this name.
    std::optional<std::size_t> find(std::string_view property_name) const;
    // Bytes of one binary record when every list is empty (scalars plus list counts).
    std::size_t min_record_bytes() const;
    // Tokens of one ASCII record when every list is empty.
    std::size_t min_record_tokens() const;
    bool has_lists() const;
};

struct PlyHeader {
    PlyFormat format = PlyFormat::ascii;
    std::vector<PlyElement> elements;  // file order
    std::size_t data_offset = 0;       // byte offset of the data section
    std::size_t num_lines = 0;         // header lines including end_header

    // Index into `elements`, if an element has this name.
    std::optional<std::size_t> find(std::string_view element_name) const;
};

// Parses the header at the start of `bytes` (the whole file). Throws IoError
// "<path>: [line <n>: ]<what>, expected <x>, got <y>" for anything outside the grammar above:
// not a PLY file, a missing end_header, an unknown format, version, keyword or type, a bad count,
// a property outside an element, duplicate element or property names.
PlyHeader parse_ply_header(std::string_view bytes, const std::filesystem::path& path);

}  // namespace pliant::io::detail
