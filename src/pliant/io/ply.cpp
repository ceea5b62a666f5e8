#include "pliant/io/ply.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/validate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/byte_order.hpp"
#include "pliant/io/detail/ply_format.hpp"
#include "pliant/io/detail/ply_header.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

using detail::load_value;
using detail::PlyElement;
using detail::PlyHeader;
using detail::PlyProperty;
using detail::PlyScalar;

namespace {

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

// What the reader does with a property's values.
enum class Role : std::uint8_t { skip, x, y, z, indices };

using Diagnostics = detail::PlyDiagnostics;

// The layout facts the decoders need, checked once against the header.
struct MeshLayout {
    std::size_t vertex_element = 0;
    std::optional<std::size_t> face_element;
    std::int64_t num_vertices = 0;
    std::vector<std::vector<Role>> roles;  // roles[element][property]
};

MeshLayout check_layout(const PlyHeader& header, const Diagnostics& diag) {
    MeshLayout layout;
    const detail::PlyMeshElements found = detail::find_mesh_elements(header, diag);
    layout.vertex_element = found.vertex_element;
    layout.face_element = found.face_element;
    layout.roles = detail::per_property(header, Role::skip);
    layout.num_vertices = static_cast<std::int64_t>(header.elements[found.vertex_element].count);
    constexpr std::array<Role, 3> AXES{Role::x, Role::y, Role::z};
    for (std::size_t axis = 0; axis < 3; ++axis) {
        layout.roles[found.vertex_element][found.xyz[axis]] = AXES[axis];
    }
    if (layout.face_element) {
        layout.roles[*layout.face_element][found.indices] = Role::indices;
    }
    return layout;
}

// Appends the fan (c0, ci, ci+1) of one polygon after checking its corners.
void add_face(std::span<const std::int64_t> corners, std::uint64_t face, std::int64_t num_vertices,
              const Diagnostics& diag, std::vector<geometry::Triangle>& triangles) {
    if (corners.size() < 3) {
        diag.fail("face {} has {} vertices, expected at least 3", face, corners.size());
    }
    for (std::size_t k = 0; k < corners.size(); ++k) {
        if (corners[k] < 0 || corners[k] >= num_vertices) {
            diag.fail("face {} corner {} has vertex index {}, expected 0 <= index < {}", face, k,
                      corners[k], num_vertices);
        }
    }
    const auto c0 = static_cast<std::int32_t>(corners[0]);
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
        const auto c1 = static_cast<std::int32_t>(corners[i]);
        const auto c2 = static_cast<std::int32_t>(corners[i + 1]);
        if (c0 == c1 || c1 == c2 || c0 == c2) {
            diag.fail(
                "face {} repeats a vertex in triangle ({}, {}, {}), expected distinct "
                "vertex indices",
                face, c0, c1, c2);
        }
        triangles.push_back({c0, c1, c2});
    }
}

void check_vertex(const Vec3d& p, std::uint64_t vertex, const Diagnostics& diag) {
    if (!is_finite(p)) {
        diag.fail(
            "vertex {} has a non-finite coordinate, expected finite x, y and z, got ({}, {}, "
            "{})",
            vertex, p.x, p.y, p.z);
    }
}

// --- binary ----------------------------------------------------------------------------------

// Decodes the binary data section in place; `data` is everything after end_header.
class BinaryDecoder {
public:
    BinaryDecoder(const PlyHeader& header, const MeshLayout& layout, std::string_view data,
                  const Diagnostics& diag, geometry::TriangleMeshD& mesh)
        : m_header(header),
          m_layout(layout),
          m_data(data),
          m_diag(diag),
          m_mesh(mesh),
          m_swap(detail::needs_swap(header.format)) {}

    void run() {
        for (std::size_t e = 0; e < m_header.elements.size(); ++e) {
            const PlyElement& element = m_header.elements[e];
            const bool is_vertex = e == m_layout.vertex_element;
            if (!element.has_lists()) {
                decode_fixed(element, m_layout.roles[e], is_vertex);
            } else if (is_common_face_layout(element, m_layout.roles[e])) {
                decode_common_faces(element, m_layout.roles[e]);
            } else {
                for (std::uint64_t r = 0; r < element.count; ++r) {
                    decode_record(element, m_layout.roles[e], r, is_vertex);
                }
            }
        }
        detail::check_binary_end(m_data.size() - m_pos, m_diag);
    }

private:
    // Records of one size: bounds are checked once for the whole element.
    void decode_fixed(const PlyElement& element, const std::vector<Role>& roles, bool is_vertex) {
        const std::size_t stride = element.min_record_bytes();
        const std::size_t left = m_data.size() - m_pos;
        if (stride > 0 && element.count > left / stride) {
            m_diag.fail(
                "truncated binary data in element '{}', expected {} records of {} bytes, "
                "got {} bytes",
                element.name, element.count, stride, left);
        }
        const std::size_t num_bytes = static_cast<std::size_t>(element.count) * stride;
        if (is_vertex) {
            std::array<std::size_t, 3> offset{};
            std::array<PlyScalar, 3> type{};
            std::size_t at = 0;
            for (std::size_t p = 0; p < element.properties.size(); ++p) {
                if (roles[p] != Role::skip) {
                    const auto axis = static_cast<std::size_t>(roles[p]) - 1;
                    offset[axis] = at;
                    type[axis] = element.properties[p].type;
                }
                at += detail::size_of(element.properties[p].type);
            }
            const char* record = m_data.data() + m_pos;
            for (std::size_t v = 0; v < element.count; ++v, record += stride) {
                const Vec3d position{load_value(record + offset[0], type[0], m_swap),
                                     load_value(record + offset[1], type[1], m_swap),
                                     load_value(record + offset[2], type[2], m_swap)};
                check_vertex(position, v, m_diag);
                m_mesh.positions[v] = position;
            }
        }
        m_pos += num_bytes;
    }

    // `property list uchar int|uint vertex_indices` alone: what nearly every writer emits.
    static bool is_common_face_layout(const PlyElement& element, const std::vector<Role>& roles) {
        if (element.properties.size() != 1 || roles[0] != Role::indices) {
            return false;
        }
        const PlyProperty& list = element.properties[0];
        return list.count_type == PlyScalar::uint8 &&
               (list.type == PlyScalar::int32 || list.type == PlyScalar::uint32);
    }

    // The fast path for the common layout: a valid triangle is decoded without the general
    // machinery; anything else (polygons, errors, truncation) goes through decode_record, which
    // also produces the error messages.
    void decode_common_faces(const PlyElement& element, const std::vector<Role>& roles) {
        constexpr std::size_t TRIANGLE_BYTES = 1 + 3 * sizeof(std::int32_t);
        const bool is_unsigned = element.properties[0].type == PlyScalar::uint32;
        const auto num_vertices = static_cast<std::uint64_t>(m_layout.num_vertices);
        for (std::uint64_t f = 0; f < element.count; ++f) {
            if (m_data.size() - m_pos >= TRIANGLE_BYTES && m_data[m_pos] == 3) {
                const char* p = m_data.data() + m_pos + 1;
                std::array<std::uint64_t, 3> c{};
                for (std::size_t k = 0; k < 3; ++k) {
                    // A negative int32 becomes a huge value and fails the range test.
                    c[k] = is_unsigned ? detail::load<std::uint32_t>(p + 4 * k, m_swap)
                                       : static_cast<std::uint64_t>(static_cast<std::int64_t>(
                                             detail::load<std::int32_t>(p + 4 * k, m_swap)));
                }
                if (c[0] < num_vertices && c[1] < num_vertices && c[2] < num_vertices &&
                    c[0] != c[1] && c[1] != c[2] && c[0] != c[2]) {
                    m_mesh.triangles.push_back({static_cast<std::int32_t>(c[0]),
                                                static_cast<std::int32_t>(c[1]),
                                                static_cast<std::int32_t>(c[2])});
                    m_pos += TRIANGLE_BYTES;
                    continue;
                }
            }
            decode_record(element, roles, f, false);
        }
    }

    // One record with lists: every read is bounds-checked.
    void decode_record(const PlyElement& element, const std::vector<Role>& roles, std::uint64_t r,
                       bool is_vertex) {
        Vec3d position;
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            if (!property.is_list) {
                const char* value = take(detail::size_of(property.type), element, r, property);
                if (roles[p] != Role::skip) {
                    position[static_cast<int>(roles[p]) - 1] =
                        load_value(value, property.type, m_swap);
                }
                continue;
            }
            const char* count_bytes =
                take(detail::size_of(property.count_type), element, r, property);
            const std::uint64_t length = detail::list_length(
                load_value(count_bytes, property.count_type, m_swap), element, r, property, m_diag);
            const std::size_t item_size = detail::size_of(property.type);
            if (length > (m_data.size() - m_pos) / item_size) {
                truncated(element, r, property, length * item_size);
            }
            const char* items = m_data.data() + m_pos;
            m_pos += static_cast<std::size_t>(length) * item_size;
            if (roles[p] == Role::indices) {
                m_corners.resize(static_cast<std::size_t>(length));
                for (std::size_t k = 0; k < m_corners.size(); ++k) {
                    m_corners[k] = static_cast<std::int64_t>(
                        load_value(items + k * item_size, property.type, m_swap));
                }
                add_face(m_corners, r, m_layout.num_vertices, m_diag, m_mesh.triangles);
            }
        }
        if (is_vertex) {
            check_vertex(position, r, m_diag);
            m_mesh.positions[r] = position;
        }
    }

    const char* take(std::size_t num_bytes, const PlyElement& element, std::uint64_t record,
                     const PlyProperty& property) {
        if (num_bytes > m_data.size() - m_pos) {
            truncated(element, record, property, num_bytes);
        }
        const char* p = m_data.data() + m_pos;
        m_pos += num_bytes;
        return p;
    }

    [[noreturn]] void truncated(const PlyElement& element, std::uint64_t record,
                                const PlyProperty& property, std::uint64_t num_bytes) const {
        detail::fail_truncated_binary(element, record, property, num_bytes, m_data.size() - m_pos,
                                      m_diag);
    }

    const PlyHeader& m_header;
    const MeshLayout& m_layout;
    std::string_view m_data;
    const Diagnostics& m_diag;
    geometry::TriangleMeshD& m_mesh;
    bool m_swap;
    std::size_t m_pos = 0;
    std::vector<std::int64_t> m_corners;  // scratch: one face's indices
};

// --- ASCII -----------------------------------------------------------------------------------

class AsciiDecoder {
public:
    AsciiDecoder(const PlyHeader& header, const MeshLayout& layout, std::string_view data,
                 Diagnostics& diag, geometry::TriangleMeshD& mesh)
        : m_header(header),
          m_layout(layout),
          m_cursor(data, header.num_lines + 1, diag),
          m_diag(diag),
          m_mesh(mesh) {}

    void run() {
        for (std::size_t e = 0; e < m_header.elements.size(); ++e) {
            const PlyElement& element = m_header.elements[e];
            if (element.properties.empty()) {
                continue;  // such records have no tokens: nothing to read
            }
            for (std::uint64_t r = 0; r < element.count; ++r) {
                decode_record(element, m_layout.roles[e], r, e == m_layout.vertex_element);
            }
        }
        m_cursor.finish();
    }

private:
    void decode_record(const PlyElement& element, const std::vector<Role>& roles, std::uint64_t r,
                       bool is_vertex) {
        m_cursor.begin_record(element, r);
        Vec3d position;
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            if (!property.is_list) {
                const double value = m_cursor.value(property.type, element, r, property, "");
                if (roles[p] != Role::skip) {
                    position[static_cast<int>(roles[p]) - 1] = value;
                }
                continue;
            }
            const std::uint64_t length = detail::list_length(
                m_cursor.value(property.count_type, element, r, property, " list length"), element,
                r, property, m_diag);
            m_corners.clear();
            for (std::uint64_t k = 0; k < length; ++k) {
                const double item = m_cursor.value(property.type, element, r, property, " item");
                if (roles[p] == Role::indices) {
                    m_corners.push_back(static_cast<std::int64_t>(item));
                }
            }
            if (roles[p] == Role::indices) {
                add_face(m_corners, r, m_layout.num_vertices, m_diag, m_mesh.triangles);
            }
        }
        m_cursor.end_record(element, r);
        if (is_vertex) {
            check_vertex(position, r, m_diag);
            m_mesh.positions[r] = position;
        }
    }

    const PlyHeader& m_header;
    const MeshLayout& m_layout;
    detail::PlyTextCursor m_cursor;
    Diagnostics& m_diag;
    geometry::TriangleMeshD& m_mesh;
    std::vector<std::int64_t> m_corners;  // scratch: one face's indices
};

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------

constexpr std::size_t FLUSH_BYTES = std::size_t{1} << 20;

void flush_if_full(fmt::memory_buffer& buffer, std::ostream& out, bool force = false) {
    if (force || buffer.size() >= FLUSH_BYTES) {
        out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
        buffer.clear();
    }
}

template <typename T>
void append_binary(fmt::memory_buffer& buffer, T value, bool swap) {
    char bytes[sizeof(T)];
    detail::store(bytes, value, swap);
    buffer.append(bytes, bytes + sizeof(T));
}

template <typename Real>
void write_ply_impl(const std::filesystem::path& path,
                    const geometry::BasicTriangleMesh<Real>& mesh, PlyFormat format) {
    detail::check_write_format(format, "write_ply", path);
    geometry::validate_mesh(mesh, path.string());

    constexpr bool IS_FLOAT = std::is_same_v<Real, float>;
    const std::string header = fmt::format(
        "ply\nformat {} 1.0\ncomment written by pliant\nelement vertex {}\nproperty {} x\n"
        "property {} y\nproperty {} z\nelement face {}\nproperty list uchar int vertex_indices\n"
        "end_header\n",
        to_string(format), mesh.num_vertices(), IS_FLOAT ? "float" : "double",
        IS_FLOAT ? "float" : "double", IS_FLOAT ? "float" : "double", mesh.num_triangles());

    write_file_atomically(path, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        fmt::memory_buffer buffer;
        if (format == PlyFormat::ascii) {
            for (const Vec3<Real>& p : mesh.positions) {
                if constexpr (IS_FLOAT) {
                    fmt::format_to(std::back_inserter(buffer), "{:.9g} {:.9g} {:.9g}\n", p.x, p.y,
                                   p.z);
                } else {
                    fmt::format_to(std::back_inserter(buffer), "{:.17g} {:.17g} {:.17g}\n", p.x,
                                   p.y, p.z);
                }
                flush_if_full(buffer, out);
            }
            for (const geometry::Triangle& t : mesh.triangles) {
                fmt::format_to(std::back_inserter(buffer), "3 {} {} {}\n", t[0], t[1], t[2]);
                flush_if_full(buffer, out);
            }
        } else {
            const bool swap = detail::needs_swap(format);
            for (const Vec3<Real>& p : mesh.positions) {
                append_binary(buffer, p.x, swap);
                append_binary(buffer, p.y, swap);
                append_binary(buffer, p.z, swap);
                flush_if_full(buffer, out);
            }
            for (const geometry::Triangle& t : mesh.triangles) {
                buffer.push_back(static_cast<char>(3));
                append_binary(buffer, t[0], swap);
                append_binary(buffer, t[1], swap);
                append_binary(buffer, t[2], swap);
                flush_if_full(buffer, out);
            }
        }
        flush_if_full(buffer, out, true);
    });
}

}  // namespace

const char* to_string(PlyFormat format) {
    switch (format) {
        case PlyFormat::ascii:
            return "ascii";
        case PlyFormat::binary_little_endian:
            return "binary_little_endian";
        case PlyFormat::binary_big_endian:
            return "binary_big_endian";
    }
    return "unknown";
}

geometry::TriangleMeshD read_ply(const std::filesystem::path& path) {
    // Step 1: the whole file in one read; the header; the layout and counts checked before any
    // allocation that depends on them.
    const std::string bytes = read_file(path);
    const PlyHeader header = detail::parse_ply_header(bytes, path);
    Diagnostics diag(path);
    const MeshLayout layout = check_layout(header, diag);
    const std::string_view data = std::string_view(bytes).substr(header.data_offset);
    detail::check_counts_fit(header, data.size(), diag);

    // Step 2: decode from memory.
    geometry::TriangleMeshD mesh;
    mesh.positions.resize(static_cast<std::size_t>(layout.num_vertices));
    if (layout.face_element) {
        // A hint only, capped by the triangles the data could hold (three indices of at least
        // one byte or token each), so that a file declaring many faces that turn out empty or
        // broken cannot make the reader reserve more than its size allows.
        const PlyElement& faces = header.elements[*layout.face_element];
        const std::size_t min_triangle_bytes = header.format == PlyFormat::ascii
                                                   ? 2 * (faces.min_record_tokens() + 3)
                                                   : faces.min_record_bytes() + 3;
        mesh.triangles.reserve(static_cast<std::size_t>(
            std::min<std::uint64_t>(faces.count, data.size() / min_triangle_bytes)));
    }
    if (header.format == PlyFormat::ascii) {
        AsciiDecoder(header, layout, data, diag, mesh).run();
    } else {
        BinaryDecoder(header, layout, data, diag, mesh).run();
    }

    // Step 3: the decoders checked indices, fans and coordinates; validate_mesh is the shared
    // definition of a valid mesh and must agree.
    try {
        geometry::validate_mesh(mesh, path.string());
    } catch (const InvalidInput& e) {
        throw IoError(e.what());
    }
    return mesh;
}

void write_ply(const std::filesystem::path& path, const geometry::TriangleMesh& mesh,
               PlyFormat format) {
    write_ply_impl(path, mesh, format);
}

void write_ply(const std::filesystem::path& path, const geometry::TriangleMeshD& mesh,
               PlyFormat format) {
    write_ply_impl(path, mesh, format);
}

void write_point_cloud_ply(const std::filesystem::path& path, std::span<const Vec3f> positions,
                           std::span<const std::array<std::uint8_t, 3>> colors, PlyFormat format) {
    detail::check_write_format(format, "write_point_cloud_ply", path);
    if (!colors.empty() && colors.size() != positions.size()) {
        throw InvalidInput(
            fmt::format("write_point_cloud_ply: {}: {} colours for {} points, expected 0 or {}",
                        path.string(), colors.size(), positions.size(), positions.size()));
    }
    geometry::validate_positions(positions, path.string());
    const bool has_colors = !colors.empty();
    const std::string header = fmt::format(
        "ply\nformat {} 1.0\ncomment written by pliant\nelement vertex {}\nproperty float x\n"
        "property float y\nproperty float z\n{}end_header\n",
        to_string(format), positions.size(),
        has_colors ? "property uchar red\nproperty uchar green\nproperty uchar blue\n" : "");
    write_file_atomically(path, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        fmt::memory_buffer buffer;
        const bool swap = detail::needs_swap(format);
        for (std::size_t i = 0; i < positions.size(); ++i) {
            const Vec3f& p = positions[i];
            if (format == PlyFormat::ascii) {
                fmt::format_to(std::back_inserter(buffer), "{:.9g} {:.9g} {:.9g}", p.x, p.y, p.z);
                if (has_colors) {
                    fmt::format_to(std::back_inserter(buffer), " {} {} {}", colors[i][0],
                                   colors[i][1], colors[i][2]);
                }
                buffer.push_back('\n');
            } else {
                append_binary(buffer, p.x, swap);
                append_binary(buffer, p.y, swap);
                append_binary(buffer, p.z, swap);
                if (has_colors) {
                    buffer.append(colors[i].begin(), colors[i].end());
                }
            }
            flush_if_full(buffer, out);
        }
        flush_if_full(buffer, out, true);
    });
}

}  // namespace pliant::io
