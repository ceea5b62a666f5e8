// The PLY data section as both PLY readers (ply.cpp: triangle meshes, ply_polygons.cpp:
// polygon meshes) decode it: error wording, the count check done before allocating, the
// element/property layout of a mesh, binary value loads and the ASCII record/token grammar.
// Header grammar and scalar types: ply_header.hpp.
#pragma once

#include <fmt/format.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/detail/ply_header.hpp"

namespace pliant::io::detail {

// Formats "<path>: [line <n>: ]<message>" IoErrors. The line is set while decoding ASCII data.
class PlyDiagnostics {
public:
    explicit PlyDiagnostics(const std::filesystem::path& path) : m_path(path.string()) {}

    void set_line(std::size_t line) { m_line = line; }

    template <typename... Args>
    [[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) const {
        const std::string message = fmt::format(format, std::forward<Args>(args)...);
        if (m_line > 0) {
            throw IoError(fmt::format("{}: line {}: {}", m_path, m_line, message));
        }
        throw IoError(fmt::format("{}: {}", m_path, message));
    }

private:
    std::string m_path;
    std::size_t m_line = 0;  // 0: binary data, no line
};

// The elements and properties every PLY mesh has: element `vertex` (at most 2^31 - 1 records)
// with scalar x, y, z, and optionally element `face` with an integer list `vertex_indices` or
// `vertex_index`.
struct PlyMeshElements {
    std::size_t vertex_element = 0;
    std::array<std::size_t, 3> xyz{};  // property indices of x, y, z in the vertex element
    std::optional<std::size_t> face_element;
    std::size_t indices = 0;  // property index of the index list (when there is a face element)
};

// Finds the mesh elements of `header`; fails (IoError via `diag`) when the vertex element, one
// of x, y, z or the face index list is missing or of the wrong kind, or there are more than
// 2^31 - 1 vertices.
PlyMeshElements find_mesh_elements(const PlyHeader& header, const PlyDiagnostics& diag);

// One `value` per property of every element: table[element][property], in header order.
template <typename T>
std::vector<std::vector<T>> per_property(const PlyHeader& header, const T& value) {
    std::vector<std::vector<T>> table(header.elements.size());
    for (std::size_t e = 0; e < header.elements.size(); ++e) {
        table[e].assign(header.elements[e].properties.size(), value);
    }
    return table;
}

// Refuses element counts that the data section cannot hold, before anything is allocated: a
// binary record takes at least min_record_bytes(), an ASCII record of k values at least 2k bytes
// (k tokens, each followed by a space or newline, except at the very end of the file).
void check_counts_fit(const PlyHeader& header, std::size_t data_bytes, const PlyDiagnostics& diag);

// Throws InvalidInput "<function>: <path>: format (<n>) is not a PlyFormat, expected one of …"
// for a value outside the enum (a writer's check before it touches the file).
void check_write_format(PlyFormat format, const char* function, const std::filesystem::path& path);

// Whether binary data of `format` must be byte-swapped on this machine.
bool needs_swap(PlyFormat format);

// One binary value at `p` (file byte order, swapped when `swap`). Every PLY scalar converts
// exactly to double (integers are at most 32 bits).
double load_value(const char* p, PlyScalar type, bool swap);

// The values of an integer PlyScalar (uint32 for the non-integer types).
struct IntegerRange {
    std::int64_t min;
    std::int64_t max;
};
IntegerRange integer_range(PlyScalar type);

// A list length read as `count`, refused when negative.
std::uint64_t list_length(double count, const PlyElement& element, std::uint64_t record,
                          const PlyProperty& property, const PlyDiagnostics& diag);

// Fails: `num_bytes` for `property` of `record` are not in the `bytes_left` of binary data.
[[noreturn]] void fail_truncated_binary(const PlyElement& element, std::uint64_t record,
                                        const PlyProperty& property, std::uint64_t num_bytes,
                                        std::size_t bytes_left, const PlyDiagnostics& diag);

// Fails unless the binary data ended exactly after the last element (`bytes_left` == 0).
void check_binary_end(std::size_t bytes_left, const PlyDiagnostics& diag);

// Walks ASCII data: one record per line, values separated by spaces, tabs (or \r); blank lines
// are allowed between records. Errors name the line of the current record.
class PlyTextCursor {
public:
    // `data`: everything after end_header, whose first line is `first_line` of the file.
    PlyTextCursor(std::string_view data, std::size_t first_line, PlyDiagnostics& diag)
        : m_data(data), m_line(first_line), m_diag(diag) {}

    // Moves to record `record` of `element` (the next non-blank line); fails at the end of data.
    void begin_record(const PlyElement& element, std::uint64_t record);
    // Fails if the record's line holds more values.
    void end_record(const PlyElement& element, std::uint64_t record);
    // Fails unless only blank lines are left.
    void finish();

    // Parses the next token of the record as `type` (the value of `property`; `part` is "",
    // " list length" or " item" for the message); fails on a missing, malformed or out-of-range
    // value. Every PLY scalar fits a double exactly.
    double value(PlyScalar type, const PlyElement& element, std::uint64_t record,
                 const PlyProperty& property, std::string_view part);

private:
    static bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r'; }
    bool next_record();
    std::string_view token();
    bool at_end() const { return m_pos >= m_data.size(); }

    std::string_view m_data;
    std::size_t m_pos = 0;
    std::size_t m_line;
    PlyDiagnostics& m_diag;
};

}  // namespace pliant::io::detail
