#include "pliant/io/detail/ply_header.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>

#include "pliant/core/error.hpp"
#include "pliant/io/detail/text.hpp"

namespace pliant::io::detail {

namespace {

constexpr std::string_view FORMAT_CHOICES = "ascii, binary_little_endian, binary_big_endian";
constexpr std::string_view TYPE_CHOICES =
    "char, uchar, short, ushort, int, uint, float, double (or int8, uint8, int16, uint16, int32, "
    "uint32, float32, float64)";

std::vector<std::string_view> split_tokens(std::string_view line) {
    std::vector<std::string_view> tokens;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) {
            ++i;
        }
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') {
            ++i;
        }
        if (i > start) {
            tokens.push_back(line.substr(start, i - start));
        }
    }
    return tokens;
}

// Walks the header line by line; knows the path and line number for messages.
class HeaderLines {
public:
    HeaderLines(std::string_view bytes, const std::filesystem::path& path)
        : m_bytes(bytes), m_path(path) {}

    // The next line without its \n or \r\n, or nullopt at the end of the file.
    std::optional<std::string_view> next() {
        if (m_pos >= m_bytes.size()) {
            return std::nullopt;
        }
        std::size_t end = m_bytes.find('\n', m_pos);
        std::size_t next_pos = end + 1;
        if (end == std::string_view::npos) {
            end = m_bytes.size();
            next_pos = end;
        }
        std::string_view line = m_bytes.substr(m_pos, end - m_pos);
        if (!line.empty() && line.back() == '\r') {
            line.remove_suffix(1);
        }
        m_pos = next_pos;
        ++m_line;
        return line;
    }

    std::size_t position() const { return m_pos; }
    std::size_t line_number() const { return m_line; }

    template <typename... Args>
    [[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) const {
        throw IoError(fmt::format("{}: line {}: {}", m_path.string(), m_line,
                                  fmt::format(format, std::forward<Args>(args)...)));
    }

private:
    std::string_view m_bytes;
    const std::filesystem::path& m_path;
    std::size_t m_pos = 0;
    std::size_t m_line = 0;
};

PlyScalar parse_type_or_fail(const HeaderLines& lines, std::string_view name) {
    const std::optional<PlyScalar> type = parse_scalar_type(name);
    if (!type) {
        lines.fail("unknown property type {}, expected one of {}", quote(name), TYPE_CHOICES);
    }
    return *type;
}

}  // namespace

std::size_t size_of(PlyScalar type) {
    switch (type) {
        case PlyScalar::int8:
        case PlyScalar::uint8:
            return 1;
        case PlyScalar::int16:
        case PlyScalar::uint16:
            return 2;
        case PlyScalar::int32:
        case PlyScalar::uint32:
        case PlyScalar::float32:
            return 4;
        case PlyScalar::float64:
            return 8;
    }
    return 0;
}

bool is_integer(PlyScalar type) {
    return type != PlyScalar::float32 && type != PlyScalar::float64;
}

const char* to_string(PlyScalar type) {
    switch (type) {
        case PlyScalar::int8:
            return "char";
        case PlyScalar::uint8:
            return "uchar";
        case PlyScalar::int16:
            return "short";
        case PlyScalar::uint16:
            return "ushort";
        case PlyScalar::int32:
            return "int";
        case PlyScalar::uint32:
            return "uint";
        case PlyScalar::float32:
            return "float";
        case PlyScalar::float64:
            return "double";
    }
    return "?";
}

std::optional<PlyScalar> parse_scalar_type(std::string_view name) {
    struct Entry {
        std::string_view name;
        PlyScalar type;
    };
    static constexpr std::array<Entry, 16> TABLE{{
        {"char", PlyScalar::int8},
        {"int8", PlyScalar::int8},
        {"uchar", PlyScalar::uint8},
        {"uint8", PlyScalar::uint8},
        {"short", PlyScalar::int16},
        {"int16", PlyScalar::int16},
        {"ushort", PlyScalar::uint16},
        {"uint16", PlyScalar::uint16},
        {"int", PlyScalar::int32},
        {"int32", PlyScalar::int32},
        {"uint", PlyScalar::uint32},
        {"uint32", PlyScalar::uint32},
        {"float", PlyScalar::float32},
        {"float32", PlyScalar::float32},
        {"double", PlyScalar::float64},
        {"float64", PlyScalar::float64},
    }};
    for (const Entry& entry : TABLE) {
        if (entry.name == name) {
            return entry.type;
        }
    }
    return std::nullopt;
}

std::optional<std::size_t> PlyElement::find(std::string_view property_name) const {
    for (std::size_t i = 0; i < properties.size(); ++i) {
        if (properties[i].name == property_name) {
            return i;
        }
    }
    return std::nullopt;
}

std::size_t PlyElement::min_record_bytes() const {
    std::size_t bytes = 0;
    for (const PlyProperty& property : properties) {
        bytes += size_of(property.is_list ? property.count_type : property.type);
    }
    return bytes;
}

std::size_t PlyElement::min_record_tokens() const {
    return properties.size();
}

bool PlyElement::has_lists() const {
    return std::any_of(properties.begin(), properties.end(),
                       [](const PlyProperty& property) { return property.is_list; });
}

std::optional<std::size_t> PlyHeader::find(std::string_view element_name) const {
    for (std::size_t i = 0; i < elements.size(); ++i) {
        if (elements[i].name == element_name) {
            return i;
        }
    }
    return std::nullopt;
}

PlyHeader parse_ply_header(std::string_view bytes, const std::filesystem::path& path) {
    if (bytes.empty()) {
        throw IoError(
            fmt::format("{}: not a PLY file, expected 'ply' on the first line, got an empty file",
                        path.string()));
    }
    HeaderLines lines(bytes, path);
    const std::string_view magic = *lines.next();
    if (magic != "ply") {
        throw IoError(fmt::format("{}: not a PLY file, expected 'ply' on the first line, got {}",
                                  path.string(), quote(magic)));
    }

    PlyHeader header;
    bool has_format = false;
    while (true) {
        const std::optional<std::string_view> line = lines.next();
        if (!line) {
            throw IoError(fmt::format(
                "{}: truncated PLY header, expected an 'end_header' line, got the end of the file "
                "after line {}",
                path.string(), lines.line_number()));
        }
        const std::vector<std::string_view> tokens = split_tokens(*line);
        if (tokens.empty()) {
            continue;
        }
        const std::string_view keyword = tokens[0];
        if (keyword == "comment" || keyword == "obj_info") {
            continue;
        }
        if (keyword == "end_header") {
            if (tokens.size() != 1) {
                lines.fail("malformed end_header line, expected 'end_header', got {}",
                           quote(*line));
            }
            break;
        }
        if (keyword == "format") {
            if (has_format) {
                lines.fail("second format line, expected one format line, got {}", quote(*line));
            }
            if (tokens.size() != 3) {
                lines.fail("malformed format line, expected 'format <{}> 1.0', got {}",
                           FORMAT_CHOICES, quote(*line));
            }
            if (tokens[1] == "ascii") {
                header.format = PlyFormat::ascii;
            } else if (tokens[1] == "binary_little_endian") {
                header.format = PlyFormat::binary_little_endian;
            } else if (tokens[1] == "binary_big_endian") {
                header.format = PlyFormat::binary_big_endian;
            } else {
                lines.fail("unknown PLY format {}, expected one of {}", quote(tokens[1]),
                           FORMAT_CHOICES);
            }
            if (tokens[2] != "1.0") {
                lines.fail("unsupported PLY version {}, expected 1.0", quote(tokens[2]));
            }
            has_format = true;
            continue;
        }
        if (keyword == "element") {
            if (tokens.size() != 3) {
                lines.fail("malformed element line, expected 'element <name> <count>', got {}",
                           quote(*line));
            }
            std::int64_t count = 0;
            if (parse_integer(tokens[2], count) != ParseStatus::ok || count < 0) {
                lines.fail("bad count for element {}, expected a non-negative integer, got {}",
                           quote(tokens[1]), quote(tokens[2]));
            }
            if (header.find(tokens[1])) {
                lines.fail("duplicate element {}, expected each element name once",
                           quote(tokens[1]));
            }
            header.elements.push_back(PlyElement{.name = std::string(tokens[1]),
                                                 .count = static_cast<std::uint64_t>(count),
                                                 .properties = {},
                                                 .line = lines.line_number()});
            continue;
        }
        if (keyword == "property") {
            if (header.elements.empty()) {
                lines.fail(
                    "property before any element, expected 'element <name> <count>' first, "
                    "got {}",
                    quote(*line));
            }
            PlyElement& element = header.elements.back();
            PlyProperty property;
            if (tokens.size() >= 2 && tokens[1] == "list") {
                if (tokens.size() != 5) {
                    lines.fail(
                        "malformed list property, expected 'property list <count type> "
                        "<item type> <name>', got {}",
                        quote(*line));
                }
                property.is_list = true;
                property.count_type = parse_type_or_fail(lines, tokens[2]);
                property.type = parse_type_or_fail(lines, tokens[3]);
                property.name = std::string(tokens[4]);
                if (!is_integer(property.count_type)) {
                    lines.fail("list {} has count type {}, expected an integer type",
                               quote(property.name), to_string(property.count_type));
                }
            } else {
                if (tokens.size() != 3) {
                    lines.fail("malformed property, expected 'property <type> <name>', got {}",
                               quote(*line));
                }
                property.type = parse_type_or_fail(lines, tokens[1]);
                property.name = std::string(tokens[2]);
            }
            if (element.find(property.name)) {
                lines.fail("duplicate property {} in element {}, expected each name once",
                           quote(property.name), quote(element.name));
            }
            element.properties.push_back(std::move(property));
            continue;
        }
        lines.fail(
            "unknown header keyword {}, expected one of format, element, property, comment, "
            "obj_info, end_header",
            quote(keyword));
    }
    if (!has_format) {
        throw IoError(fmt::format("{}: PLY header has no format line, expected 'format <{}> 1.0'",
                                  path.string(), FORMAT_CHOICES));
    }
    header.data_offset = lines.position();
    header.num_lines = lines.line_number();
    return header;
}

}  // namespace pliant::io::detail
