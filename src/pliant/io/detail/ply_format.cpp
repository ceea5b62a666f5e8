#include "pliant/io/detail/ply_format.hpp"

#include <algorithm>
#include <bit>
#include <limits>

#include "pliant/io/detail/byte_order.hpp"
#include "pliant/io/detail/text.hpp"

namespace pliant::io::detail {

PlyMeshElements find_mesh_elements(const PlyHeader& header, const PlyDiagnostics& diag) {
    PlyMeshElements found;
    const std::optional<std::size_t> vertex = header.find("vertex");
    if (!vertex) {
        diag.fail("PLY header has no vertex element, expected 'element vertex <count>'");
    }
    found.vertex_element = *vertex;
    const PlyElement& vertices = header.elements[*vertex];
    constexpr std::uint64_t MAX_VERTICES = std::numeric_limits<std::int32_t>::max();
    if (vertices.count > MAX_VERTICES) {
        diag.fail("line {}: element 'vertex' has {} vertices, expected at most {} (32-bit indices)",
                  vertices.line, vertices.count, MAX_VERTICES);
    }
    constexpr std::array<const char*, 3> AXES{"x", "y", "z"};
    for (std::size_t axis = 0; axis < 3; ++axis) {
        const char* name = AXES[axis];
        const std::optional<std::size_t> p = vertices.find(name);
        if (!p) {
            diag.fail(
                "element 'vertex' has no property '{}', expected scalar properties x, y and z",
                name);
        }
        if (vertices.properties[*p].is_list) {
            diag.fail("property '{}' of element 'vertex' is a list, expected a scalar", name);
        }
        found.xyz[axis] = *p;
    }

    found.face_element = header.find("face");
    if (found.face_element) {
        const PlyElement& faces = header.elements[*found.face_element];
        std::optional<std::size_t> p = faces.find("vertex_indices");
        if (!p) {
            p = faces.find("vertex_index");
        }
        if (!p) {
            diag.fail(
                "element 'face' has no property 'vertex_indices', expected a list property "
                "named vertex_indices or vertex_index");
        }
        const PlyProperty& indices = faces.properties[*p];
        if (!indices.is_list) {
            diag.fail("property '{}' of element 'face' is a scalar, expected a list", indices.name);
        }
        if (!is_integer(indices.type)) {
            diag.fail("list '{}' of element 'face' has item type {}, expected an integer type",
                      indices.name, to_string(indices.type));
        }
        found.indices = *p;
    }
    return found;
}

void check_counts_fit(const PlyHeader& header, std::size_t data_bytes, const PlyDiagnostics& diag) {
    const bool is_ascii = header.format == PlyFormat::ascii;
    std::uint64_t remaining = data_bytes;
    for (const PlyElement& element : header.elements) {
        const std::uint64_t min_bytes =
            is_ascii ? 2 * element.min_record_tokens() : element.min_record_bytes();
        if (min_bytes == 0) {
            continue;
        }
        const std::uint64_t capacity =
            is_ascii ? (remaining + 1) / min_bytes : remaining / min_bytes;
        if (element.count > capacity) {
            diag.fail(
                "line {}: truncated data or wrong count: element '{}' declares {} records "
                "of at least {} bytes, expected at most {} in the {} bytes of data left",
                element.line, element.name, element.count, min_bytes, capacity, remaining);
        }
        remaining -= std::min(remaining, element.count * min_bytes);
    }
}

void check_write_format(PlyFormat format, const char* function, const std::filesystem::path& path) {
    if (format != PlyFormat::ascii && format != PlyFormat::binary_little_endian &&
        format != PlyFormat::binary_big_endian) {
        throw InvalidInput(
            fmt::format("{}: {}: format ({}) is not a PlyFormat, expected one of ascii, "
                        "binary_little_endian, binary_big_endian",
                        function, path.string(), static_cast<int>(format)));
    }
}

bool needs_swap(PlyFormat format) {
    return needs_swap(format == PlyFormat::binary_big_endian ? std::endian::big
                                                             : std::endian::little);
}

double load_value(const char* p, PlyScalar type, bool swap) {
    switch (type) {
        case PlyScalar::int8:
            return load<std::int8_t>(p, swap);
        case PlyScalar::uint8:
            return load<std::uint8_t>(p, swap);
        case PlyScalar::int16:
            return load<std::int16_t>(p, swap);
        case PlyScalar::uint16:
            return load<std::uint16_t>(p, swap);
        case PlyScalar::int32:
            return load<std::int32_t>(p, swap);
        case PlyScalar::uint32:
            return load<std::uint32_t>(p, swap);
        case PlyScalar::float32:
            return static_cast<double>(load<float>(p, swap));
        case PlyScalar::float64:
            return load<double>(p, swap);
    }
    return 0.0;
}

IntegerRange integer_range(PlyScalar type) {
    switch (type) {
        case PlyScalar::int8:
            return {INT8_MIN, INT8_MAX};
        case PlyScalar::uint8:
            return {0, UINT8_MAX};
        case PlyScalar::int16:
            return {INT16_MIN, INT16_MAX};
        case PlyScalar::uint16:
            return {0, UINT16_MAX};
        case PlyScalar::int32:
            return {INT32_MIN, INT32_MAX};
        default:
            return {0, UINT32_MAX};
    }
}

std::uint64_t list_length(double count, const PlyElement& element, std::uint64_t record,
                          const PlyProperty& property, const PlyDiagnostics& diag) {
    if (count < 0) {
        diag.fail(
            "list '{}' of element '{}' record {} has length {}, expected a non-negative length",
            property.name, element.name, record, count);
    }
    return static_cast<std::uint64_t>(count);
}

void fail_truncated_binary(const PlyElement& element, std::uint64_t record,
                           const PlyProperty& property, std::uint64_t num_bytes,
                           std::size_t bytes_left, const PlyDiagnostics& diag) {
    diag.fail(
        "truncated binary data in element '{}' record {} of {}, expected {} bytes for property "
        "'{}', got {}",
        element.name, record, element.count, num_bytes, property.name, bytes_left);
}

void check_binary_end(std::size_t bytes_left, const PlyDiagnostics& diag) {
    if (bytes_left != 0) {
        diag.fail(
            "{} bytes of unexpected data after the last element, expected the end of the file "
            "(do the header's counts and types match the data?)",
            bytes_left);
    }
}

void PlyTextCursor::begin_record(const PlyElement& element, std::uint64_t record) {
    if (!next_record()) {
        m_diag.set_line(m_line);
        m_diag.fail("truncated data, expected {} records of element '{}', got {}", element.count,
                    element.name, record);
    }
    m_diag.set_line(m_line);
}

void PlyTextCursor::end_record(const PlyElement& element, std::uint64_t record) {
    const std::string_view extra = token();
    if (!extra.empty()) {
        m_diag.fail("extra value {} after element '{}' record {}, expected the end of the line",
                    quote(extra), element.name, record);
    }
}

void PlyTextCursor::finish() {
    if (next_record()) {
        m_diag.set_line(m_line);
        m_diag.fail("unexpected data after the last element, expected the end of the file, got {}",
                    quote(token()));
    }
}

double PlyTextCursor::value(PlyScalar type, const PlyElement& element, std::uint64_t record,
                            const PlyProperty& property, std::string_view part) {
    const std::string_view text = token();
    if (text.empty()) {
        m_diag.fail(
            "{}data in element '{}' record {}, expected a {} value for property '{}'{}, got the "
            "end of the {}",
            at_end() ? "truncated " : "missing ", element.name, record, to_string(type),
            property.name, part, at_end() ? "file" : "line");
    }
    ParseStatus status = ParseStatus::ok;
    if (type == PlyScalar::float32) {
        float v = 0;
        status = parse_real(text, v);
        if (status == ParseStatus::ok) {
            return v;
        }
    } else if (type == PlyScalar::float64) {
        double v = 0;
        status = parse_real(text, v);
        if (status == ParseStatus::ok) {
            return v;
        }
    } else {
        std::int64_t v = 0;
        status = parse_integer(text, v);
        const IntegerRange range = integer_range(type);
        if (status == ParseStatus::ok) {
            if (v >= range.min && v <= range.max) {
                return static_cast<double>(v);
            }
            status = ParseStatus::out_of_range;
        }
        if (status == ParseStatus::out_of_range) {
            m_diag.fail(
                "bad value for property '{}'{} of element '{}' record {}, expected a {} in [{}, "
                "{}], got {}",
                property.name, part, element.name, record, to_string(type), range.min, range.max,
                quote(text));
        }
    }
    m_diag.fail(
        "bad value for property '{}'{} of element '{}' record {}, expected {} {}, got {}",
        property.name, part, element.name, record,
        status == ParseStatus::out_of_range ? "a value in the range of" : "a number of type",
        to_string(type), quote(text));
}

bool PlyTextCursor::next_record() {
    while (m_pos < m_data.size()) {
        const char c = m_data[m_pos];
        if (c == '\n') {
            ++m_line;
        } else if (!is_blank(c)) {
            return true;
        }
        ++m_pos;
    }
    return false;
}

std::string_view PlyTextCursor::token() {
    while (m_pos < m_data.size() && is_blank(m_data[m_pos])) {
        ++m_pos;
    }
    const std::size_t start = m_pos;
    while (m_pos < m_data.size() && !is_blank(m_data[m_pos]) && m_data[m_pos] != '\n') {
        ++m_pos;
    }
    return m_data.substr(start, m_pos - start);
}

}  // namespace pliant::io::detail
