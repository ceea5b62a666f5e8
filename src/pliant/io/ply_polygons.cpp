#include "pliant/io/ply_polygons.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/normals.hpp"
#include "pliant/geometry/validate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/byte_order.hpp"
#include "pliant/io/detail/ply_format.hpp"
#include "pliant/io/detail/ply_header.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

using detail::PlyElement;
using detail::PlyHeader;
using detail::PlyProperty;
using detail::PlyScalar;

namespace {

constexpr std::int64_t MAX_INDEX = std::numeric_limits<std::int32_t>::max();

// ---------------------------------------------------------------------------------------------
// Reading
// ---------------------------------------------------------------------------------------------

// What the reader does with a property's values.
enum class Role : std::uint8_t {
    skip,
    x,
    y,
    z,
    u,
    v,
    nx,
    ny,
    nz,
    vertex_attribute,
    indices,
    texcoord,
    face_attribute
};

struct Slot {
    Role role = Role::skip;
    std::size_t attribute = 0;  // vertex_attribute, face_attribute: index into the mesh's list
};

using Diagnostics = detail::PlyDiagnostics;

struct Layout {
    std::size_t vertex_element = 0;
    std::optional<std::size_t> face_element;
    bool has_vertex_uvs = false;
    bool has_normals = false;
    bool has_texcoord = false;
    std::vector<std::vector<Slot>> slots;  // slots[element][property]
};

// The scalar (not list) property of `element` named `name`, if any.
std::optional<std::size_t> find_scalar(const PlyElement& element, std::string_view name) {
    const std::optional<std::size_t> p = element.find(name);
    if (p && !element.properties[*p].is_list) {
        return p;
    }
    return std::nullopt;
}

// Assigns every property a role and declares the kept attributes in `mesh`.
Layout check_layout(const PlyHeader& header, const Diagnostics& diag, PolygonMesh& mesh) {
    Layout layout;
    const detail::PlyMeshElements found = detail::find_mesh_elements(header, diag);
    layout.vertex_element = found.vertex_element;
    layout.face_element = found.face_element;
    layout.slots = detail::per_property(header, Slot{});

    // Vertices: positions, one UV pair, normals, the other scalars as attributes.
    const PlyElement& vertices = header.elements[found.vertex_element];
    std::vector<Slot>& vertex_slots = layout.slots[found.vertex_element];
    constexpr std::array<Role, 3> AXES{Role::x, Role::y, Role::z};
    for (std::size_t axis = 0; axis < 3; ++axis) {
        vertex_slots[found.xyz[axis]].role = AXES[axis];
    }
    constexpr std::array<std::pair<const char*, const char*>, 4> UV_NAMES{
        {{"s", "t"}, {"u", "v"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}}};
    for (const auto& [u_name, v_name] : UV_NAMES) {
        const std::optional<std::size_t> u = find_scalar(vertices, u_name);
        const std::optional<std::size_t> v = find_scalar(vertices, v_name);
        if (u && v) {
            vertex_slots[*u].role = Role::u;
            vertex_slots[*v].role = Role::v;
            layout.has_vertex_uvs = true;
            break;
        }
    }
    const std::optional<std::size_t> nx = find_scalar(vertices, "nx");
    const std::optional<std::size_t> ny = find_scalar(vertices, "ny");
    const std::optional<std::size_t> nz = find_scalar(vertices, "nz");
    if (nx && ny && nz) {
        vertex_slots[*nx].role = Role::nx;
        vertex_slots[*ny].role = Role::ny;
        vertex_slots[*nz].role = Role::nz;
        layout.has_normals = true;
    }
    for (std::size_t p = 0; p < vertices.properties.size(); ++p) {
        const PlyProperty& property = vertices.properties[p];
        if (vertex_slots[p].role == Role::skip && !property.is_list) {
            vertex_slots[p] = {Role::vertex_attribute, mesh.vertex_attributes.size()};
            mesh.vertex_attributes.push_back({property.name, detail::to_string(property.type), {}});
        }
    }

    // Faces: the polygon, per-corner UVs, the other scalars as attributes.
    if (layout.face_element) {
        const PlyElement& faces = header.elements[*layout.face_element];
        std::vector<Slot>& face_slots = layout.slots[*layout.face_element];
        face_slots[found.indices].role = Role::indices;
        if (const std::optional<std::size_t> t = faces.find("texcoord")) {
            if (!faces.properties[*t].is_list) {
                diag.fail(
                    "property 'texcoord' of element 'face' is a scalar, expected a list of u, v "
                    "per corner");
            }
            face_slots[*t].role = Role::texcoord;
            layout.has_texcoord = true;
        }
        for (std::size_t q = 0; q < faces.properties.size(); ++q) {
            const PlyProperty& property = faces.properties[q];
            if (face_slots[q].role == Role::skip && !property.is_list) {
                face_slots[q] = {Role::face_attribute, mesh.face_attributes.size()};
                mesh.face_attributes.push_back(
                    {property.name, detail::to_string(property.type), {}});
            }
        }
    }
    return layout;
}

// Binary data: values in file order from `data` (everything after end_header).
class BinarySource {
public:
    BinarySource(std::string_view data, PlyFormat format, const Diagnostics& diag)
        : m_data(data), m_diag(diag), m_swap(detail::needs_swap(format)) {}

    void begin_record(const PlyElement& /*element*/, std::uint64_t /*record*/) {}
    void end_record(const PlyElement& /*element*/, std::uint64_t /*record*/) {}

    double value(PlyScalar type, const PlyElement& element, std::uint64_t record,
                 const PlyProperty& property, std::string_view /*part*/) {
        const std::size_t size = detail::size_of(type);
        if (size > m_data.size() - m_pos) {
            truncated(element, record, property, size);
        }
        const double v = detail::load_value(m_data.data() + m_pos, type, m_swap);
        m_pos += size;
        return v;
    }

    // Refuses a list of `length` items that the data left cannot hold (before it is read).
    void check_list(std::uint64_t length, const PlyElement& element, std::uint64_t record,
                    const PlyProperty& property) const {
        const std::size_t item_size = detail::size_of(property.type);
        if (length > (m_data.size() - m_pos) / item_size) {
            truncated(element, record, property, length * item_size);
        }
    }

    void skip_list(std::uint64_t length, const PlyElement& element, std::uint64_t record,
                   const PlyProperty& property) {
        check_list(length, element, record, property);
        m_pos += static_cast<std::size_t>(length) * detail::size_of(property.type);
    }

    void finish() const { detail::check_binary_end(m_data.size() - m_pos, m_diag); }

private:
    [[noreturn]] void truncated(const PlyElement& element, std::uint64_t record,
                                const PlyProperty& property, std::uint64_t num_bytes) const {
        detail::fail_truncated_binary(element, record, property, num_bytes, m_data.size() - m_pos,
                                      m_diag);
    }

    std::string_view m_data;
    const Diagnostics& m_diag;
    bool m_swap;
    std::size_t m_pos = 0;
};

// ASCII data: one record per line, values separated by spaces or tabs; blank lines allowed.
class AsciiSource {
public:
    AsciiSource(std::string_view data, std::size_t first_line, Diagnostics& diag)
        : m_cursor(data, first_line, diag) {}

    void begin_record(const PlyElement& element, std::uint64_t record) {
        m_cursor.begin_record(element, record);
    }
    void end_record(const PlyElement& element, std::uint64_t record) {
        m_cursor.end_record(element, record);
    }
    double value(PlyScalar type, const PlyElement& element, std::uint64_t record,
                 const PlyProperty& property, std::string_view part) {
        return m_cursor.value(type, element, record, property, part);
    }

    // A list's items are read one token at a time: a length beyond the line fails at its end.
    void check_list(std::uint64_t /*length*/, const PlyElement& /*element*/,
                    std::uint64_t /*record*/, const PlyProperty& /*property*/) const {}

    void skip_list(std::uint64_t length, const PlyElement& element, std::uint64_t record,
                   const PlyProperty& property) {
        for (std::uint64_t k = 0; k < length; ++k) {
            m_cursor.value(property.type, element, record, property, " item");
        }
    }

    void finish() { m_cursor.finish(); }

private:
    detail::PlyTextCursor m_cursor;
};

// Walks every record of every element through a Source (BinarySource or AsciiSource) and builds
// the mesh.
template <typename Source>
class Decoder {
public:
    Decoder(const PlyHeader& header, const Layout& layout, Source& source, const Diagnostics& diag,
            PolygonMesh& mesh)
        : m_header(header), m_layout(layout), m_source(source), m_diag(diag), m_mesh(mesh) {}

    void run() {
        const std::size_t num_vertices = m_header.elements[m_layout.vertex_element].count;
        m_mesh.positions.resize(num_vertices);
        if (m_layout.has_vertex_uvs) {
            m_vertex_uvs.resize(num_vertices);
        }
        if (m_layout.has_normals) {
            m_mesh.normals.resize(num_vertices);
        }
        for (PolygonMesh::Attribute& attribute : m_mesh.vertex_attributes) {
            attribute.values.resize(num_vertices);
        }
        for (std::size_t e = 0; e < m_header.elements.size(); ++e) {
            const PlyElement& element = m_header.elements[e];
            if (element.properties.empty()) {
                continue;  // such records have no bytes or tokens: nothing to read
            }
            const bool is_vertex = e == m_layout.vertex_element;
            const bool is_face = e == m_layout.face_element;
            for (std::uint64_t r = 0; r < element.count; ++r) {
                m_source.begin_record(element, r);
                decode_record(element, m_layout.slots[e], r);
                m_source.end_record(element, r);
                if (is_vertex) {
                    finish_vertex(r);
                } else if (is_face) {
                    finish_face(r);
                }
            }
        }
        m_source.finish();
        if (m_layout.has_vertex_uvs && !m_layout.has_texcoord) {
            m_mesh.uvs = std::move(m_vertex_uvs);
        }
    }

private:
    void decode_record(const PlyElement& element, const std::vector<Slot>& slots, std::uint64_t r) {
        for (std::size_t p = 0; p < element.properties.size(); ++p) {
            const PlyProperty& property = element.properties[p];
            const Slot slot = slots[p];
            if (!property.is_list) {
                const double value = m_source.value(property.type, element, r, property, "");
                store(slot, r, value);
                continue;
            }
            const std::uint64_t length = detail::list_length(
                m_source.value(property.count_type, element, r, property, " list length"), element,
                r, property, m_diag);
            if (slot.role == Role::skip) {
                m_source.skip_list(length, element, r, property);
                continue;
            }
            m_source.check_list(length, element, r, property);
            std::vector<double>& items = slot.role == Role::indices ? m_corners : m_texcoord;
            items.clear();
            for (std::uint64_t k = 0; k < length; ++k) {
                items.push_back(m_source.value(property.type, element, r, property, " item"));
            }
        }
    }

    void store(const Slot& slot, std::uint64_t r, double value) {
        switch (slot.role) {
            case Role::x:
                m_position.x = value;
                break;
            case Role::y:
                m_position.y = value;
                break;
            case Role::z:
                m_position.z = value;
                break;
            case Role::u:
                m_uv[0] = value;
                break;
            case Role::v:
                m_uv[1] = value;
                break;
            case Role::nx:
                m_normal.x = value;
                break;
            case Role::ny:
                m_normal.y = value;
                break;
            case Role::nz:
                m_normal.z = value;
                break;
            case Role::vertex_attribute:
                m_mesh.vertex_attributes[slot.attribute].values[r] = value;
                break;
            case Role::face_attribute:
                m_mesh.face_attributes[slot.attribute].values.push_back(value);
                break;
            default:
                break;
        }
    }

    void finish_vertex(std::uint64_t r) {
        if (!is_finite(m_position)) {
            m_diag.fail(
                "vertex {} has a non-finite coordinate, expected finite x, y and z, got ({}, "
                "{}, {})",
                r, m_position.x, m_position.y, m_position.z);
        }
        m_mesh.positions[r] = m_position;
        if (m_layout.has_vertex_uvs) {
            if (!std::isfinite(m_uv[0]) || !std::isfinite(m_uv[1])) {
                m_diag.fail(
                    "vertex {} has a non-finite texture coordinate, expected finite values, got "
                    "({}, {})",
                    r, m_uv[0], m_uv[1]);
            }
            m_vertex_uvs[r] = m_uv;
        }
        if (m_layout.has_normals) {
            m_mesh.normals[r] = m_normal;
        }
    }

    void finish_face(std::uint64_t f) {
        const std::vector<double>& corners = m_corners;
        const auto num_vertices = static_cast<double>(m_mesh.positions.size());
        if (corners.size() < 3) {
            m_diag.fail("face {} has {} vertices, expected at least 3", f, corners.size());
        }
        for (std::size_t k = 0; k < corners.size(); ++k) {
            if (corners[k] < 0 || corners[k] >= num_vertices) {
                m_diag.fail("face {} corner {} has vertex index {}, expected 0 <= index < {}", f, k,
                            corners[k], m_mesh.positions.size());
            }
        }
        // Distinct corners: sorted copy (a polygon may have many corners).
        m_sorted.assign(corners.begin(), corners.end());
        std::sort(m_sorted.begin(), m_sorted.end());
        if (const auto twin = std::adjacent_find(m_sorted.begin(), m_sorted.end());
            twin != m_sorted.end()) {
            m_diag.fail("face {} repeats vertex {}, expected distinct vertex indices", f, *twin);
        }
        const auto start = static_cast<std::int64_t>(m_mesh.corner_vertices.size());
        if (start + static_cast<std::int64_t>(corners.size()) > MAX_INDEX) {
            m_diag.fail("face {} brings the corners to more than {}, expected at most {} in all", f,
                        MAX_INDEX, MAX_INDEX);
        }
        if (m_layout.has_texcoord) {
            if (m_texcoord.size() != 2 * corners.size()) {
                m_diag.fail(
                    "face {} has {} texcoord values for {} corners, expected {} (u, v per "
                    "corner)",
                    f, m_texcoord.size(), corners.size(), 2 * corners.size());
            }
            for (std::size_t k = 0; k < corners.size(); ++k) {
                const std::array<double, 2> uv{m_texcoord[2 * k], m_texcoord[2 * k + 1]};
                if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) {
                    m_diag.fail(
                        "face {} corner {} has a non-finite texcoord, expected finite values, "
                        "got ({}, {})",
                        f, k, uv[0], uv[1]);
                }
                m_mesh.corner_uvs.push_back(static_cast<std::int32_t>(m_mesh.uvs.size()));
                m_mesh.uvs.push_back(uv);
            }
        }
        for (const double c : corners) {
            const auto v = static_cast<std::int32_t>(c);
            m_mesh.corner_vertices.push_back(v);
            if (!m_layout.has_texcoord) {
                m_mesh.corner_uvs.push_back(m_layout.has_vertex_uvs ? v : -1);
            }
            m_mesh.corner_normals.push_back(m_layout.has_normals ? v : -1);
        }
        m_mesh.face_starts.push_back(static_cast<std::int32_t>(m_mesh.corner_vertices.size()));
        m_mesh.face_tags.emplace_back();
    }

    const PlyHeader& m_header;
    const Layout& m_layout;
    Source& m_source;
    const Diagnostics& m_diag;
    PolygonMesh& m_mesh;
    // One record's values.
    Vec3d m_position;
    std::array<double, 2> m_uv{};
    Vec3d m_normal;
    std::vector<double> m_corners;
    std::vector<double> m_texcoord;
    std::vector<double> m_sorted;  // scratch
    std::vector<std::array<double, 2>> m_vertex_uvs;
};

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------

constexpr std::size_t FLUSH_BYTES = std::size_t{1} << 20;

template <typename T>
void append_binary(fmt::memory_buffer& buffer, T value, bool swap) {
    char bytes[sizeof(T)];
    detail::store(bytes, value, swap);
    buffer.append(bytes, bytes + sizeof(T));
}

// Appends `value` as a PLY value of `type` (binary) or its text followed by `separator` (ASCII).
void append_value(fmt::memory_buffer& buffer, double value, PlyScalar type, PlyFormat format,
                  bool swap) {
    if (format == PlyFormat::ascii) {
        if (type == PlyScalar::float32) {
            fmt::format_to(std::back_inserter(buffer), " {:.9g}", static_cast<float>(value));
        } else if (type == PlyScalar::float64) {
            fmt::format_to(std::back_inserter(buffer), " {:.17g}", value);
        } else {
            fmt::format_to(std::back_inserter(buffer), " {}", static_cast<std::int64_t>(value));
        }
        return;
    }
    switch (type) {
        case PlyScalar::int8:
            append_binary(buffer, static_cast<std::int8_t>(value), swap);
            break;
        case PlyScalar::uint8:
            append_binary(buffer, static_cast<std::uint8_t>(value), swap);
            break;
        case PlyScalar::int16:
            append_binary(buffer, static_cast<std::int16_t>(value), swap);
            break;
        case PlyScalar::uint16:
            append_binary(buffer, static_cast<std::uint16_t>(value), swap);
            break;
        case PlyScalar::int32:
            append_binary(buffer, static_cast<std::int32_t>(value), swap);
            break;
        case PlyScalar::uint32:
            append_binary(buffer, static_cast<std::uint32_t>(value), swap);
            break;
        case PlyScalar::float32:
            append_binary(buffer, static_cast<float>(value), swap);
            break;
        case PlyScalar::float64:
            append_binary(buffer, value, swap);
            break;
    }
}

// The attributes' types, checked: a known PLY type and one value per vertex or face.
std::vector<PlyScalar> check_attributes(const std::vector<PolygonMesh::Attribute>& attributes,
                                        std::size_t count, const char* what,
                                        const std::filesystem::path& path) {
    std::vector<PlyScalar> types;
    for (const PolygonMesh::Attribute& attribute : attributes) {
        const std::optional<PlyScalar> type = detail::parse_scalar_type(attribute.type);
        if (!type) {
            throw InvalidInput(fmt::format(
                "{}: {} attribute '{}' has type '{}', expected a PLY scalar type (char uchar "
                "short ushort int uint float double)",
                path.string(), what, attribute.name, attribute.type));
        }
        if (attribute.values.size() != count) {
            throw InvalidInput(fmt::format("{}: {} attribute '{}' has {} values, expected {}",
                                           path.string(), what, attribute.name,
                                           attribute.values.size(), count));
        }
        for (std::size_t k = 0; k < attribute.values.size(); ++k) {
            const double value = attribute.values[k];
            bool fits = true;
            if (detail::is_integer(*type)) {
                const detail::IntegerRange range = detail::integer_range(*type);
                fits = value == std::floor(value) && value >= static_cast<double>(range.min) &&
                       value <= static_cast<double>(range.max);
            } else if (*type == PlyScalar::float32 && std::isfinite(value)) {
                fits = std::abs(value) <= static_cast<double>(std::numeric_limits<float>::max());
            }
            if (!fits) {
                throw InvalidInput(
                    fmt::format("{}: {} attribute '{}' value {} is {}, expected a {} value",
                                path.string(), what, attribute.name, k, value, attribute.type));
            }
        }
        types.push_back(*type);
    }
    return types;
}

}  // namespace

PolygonMesh read_ply_polygons(const std::filesystem::path& path) {
    // Step 1: the whole file in one read; the header; the layout and counts checked before any
    // allocation that depends on them.
    const std::string bytes = read_file(path);
    const PlyHeader header = detail::parse_ply_header(bytes, path);
    Diagnostics diag(path);
    PolygonMesh mesh;
    const Layout layout = check_layout(header, diag, mesh);
    const std::string_view data = std::string_view(bytes).substr(header.data_offset);
    detail::check_counts_fit(header, data.size(), diag);

    // Step 2: decode from memory.
    if (header.format == PlyFormat::ascii) {
        AsciiSource source(data, header.num_lines + 1, diag);
        Decoder<AsciiSource>(header, layout, source, diag, mesh).run();
    } else {
        BinarySource source(data, header.format, diag);
        Decoder<BinarySource>(header, layout, source, diag, mesh).run();
    }
    return mesh;
}

void write_ply_polygons(const std::filesystem::path& path, const PolygonMesh& mesh,
                        std::span<const Vec3d> positions, PlyFormat format) {
    // Step 1: checks, normals and the UV layout, before touching the file.
    detail::check_write_format(format, "write_ply_polygons", path);
    if (positions.size() != mesh.positions.size()) {
        throw InvalidInput(fmt::format("{}: expected {} positions (the mesh's vertices), got {}",
                                       path.string(), mesh.positions.size(), positions.size()));
    }
    geometry::validate_positions(positions, path.string());
    const std::vector<PlyScalar> vertex_types =
        check_attributes(mesh.vertex_attributes, positions.size(), "vertex", path);
    const std::vector<PlyScalar> face_types =
        check_attributes(mesh.face_attributes, mesh.num_faces(), "face", path);
    const geometry::TriangleMeshD triangles = triangulate(mesh);
    std::vector<Vec3f> normals;
    std::vector<Vec3d> sums;
    geometry::vertex_normals(positions, triangles.triangles, normals, sums);

    // One UV per vertex when every corner has one and a vertex's corners agree.
    const bool has_uvs = std::any_of(mesh.corner_uvs.begin(), mesh.corner_uvs.end(),
                                     [](std::int32_t t) { return t >= 0; });
    bool per_vertex_uvs = has_uvs;
    std::vector<std::array<double, 2>> vertex_uvs;
    if (has_uvs) {
        vertex_uvs.assign(positions.size(), {0.0, 0.0});
        std::vector<bool> is_set(positions.size(), false);
        for (std::size_t c = 0; c < mesh.corner_vertices.size() && per_vertex_uvs; ++c) {
            const std::int32_t t = mesh.corner_uvs[c];
            const auto v = static_cast<std::size_t>(mesh.corner_vertices[c]);
            if (t >= 0 && !is_set[v]) {
                vertex_uvs[v] = mesh.uvs[static_cast<std::size_t>(t)];
                is_set[v] = true;
            } else {
                per_vertex_uvs = t >= 0 && vertex_uvs[v] == mesh.uvs[static_cast<std::size_t>(t)];
            }
        }
    }
    const bool per_corner_uvs = has_uvs && !per_vertex_uvs;
    std::int32_t max_corners = 0;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        max_corners = std::max(max_corners, mesh.face_starts[f + 1] - mesh.face_starts[f]);
    }
    const PlyScalar count_type = max_corners > 255 ? PlyScalar::int32 : PlyScalar::uint8;

    // Step 2: the header.
    std::string header = fmt::format(
        "ply\nformat {} 1.0\ncomment written by pliant\nelement vertex {}\n"
        "property double x\nproperty double y\nproperty double z\n"
        "property float nx\nproperty float ny\nproperty float nz\n",
        to_string(format), positions.size());
    if (per_vertex_uvs) {
        header += "property float s\nproperty float t\n";
    }
    for (const PolygonMesh::Attribute& attribute : mesh.vertex_attributes) {
        header += fmt::format("property {} {}\n", attribute.type, attribute.name);
    }
    header += fmt::format("element face {}\nproperty list {} int vertex_indices\n",
                          mesh.num_faces(), detail::to_string(count_type));
    if (per_corner_uvs) {
        header += fmt::format("property list {} float texcoord\n", detail::to_string(count_type));
    }
    for (const PolygonMesh::Attribute& attribute : mesh.face_attributes) {
        header += fmt::format("property {} {}\n", attribute.type, attribute.name);
    }
    header += "end_header\n";

    // Step 3: the data, streamed.
    const bool swap = detail::needs_swap(format);
    const bool is_ascii = format == PlyFormat::ascii;
    write_file_atomically(path, [&](std::ostream& out) {
        out.write(header.data(), static_cast<std::streamsize>(header.size()));
        fmt::memory_buffer buffer;
        const auto end_record = [&] {
            if (is_ascii) {
                buffer.push_back('\n');
            }
            if (buffer.size() >= FLUSH_BYTES) {
                out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                buffer.clear();
            }
        };
        // ASCII values are written with a leading space; each record drops its first one.
        const auto begin_record = [&] {
            return buffer.size() + (is_ascii ? 1 : 0);
        };
        const auto trim_first_space = [&](std::size_t at) {
            if (is_ascii && at <= buffer.size()) {
                std::copy(buffer.begin() + static_cast<std::ptrdiff_t>(at), buffer.end(),
                          buffer.begin() + static_cast<std::ptrdiff_t>(at - 1));
                buffer.resize(buffer.size() - 1);
            }
        };
        for (std::size_t v = 0; v < positions.size(); ++v) {
            const std::size_t at = begin_record();
            append_value(buffer, positions[v].x, PlyScalar::float64, format, swap);
            append_value(buffer, positions[v].y, PlyScalar::float64, format, swap);
            append_value(buffer, positions[v].z, PlyScalar::float64, format, swap);
            append_value(buffer, normals[v].x, PlyScalar::float32, format, swap);
            append_value(buffer, normals[v].y, PlyScalar::float32, format, swap);
            append_value(buffer, normals[v].z, PlyScalar::float32, format, swap);
            if (per_vertex_uvs) {
                append_value(buffer, vertex_uvs[v][0], PlyScalar::float32, format, swap);
                append_value(buffer, vertex_uvs[v][1], PlyScalar::float32, format, swap);
            }
            for (std::size_t a = 0; a < vertex_types.size(); ++a) {
                append_value(buffer, mesh.vertex_attributes[a].values[v], vertex_types[a], format,
                             swap);
            }
            trim_first_space(at);
            end_record();
        }
        for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
            const std::size_t at = begin_record();
            const auto first = static_cast<std::size_t>(mesh.face_starts[f]);
            const auto last = static_cast<std::size_t>(mesh.face_starts[f + 1]);
            append_value(buffer, static_cast<double>(last - first), count_type, format, swap);
            for (std::size_t c = first; c < last; ++c) {
                append_value(buffer, mesh.corner_vertices[c], PlyScalar::int32, format, swap);
            }
            if (per_corner_uvs) {
                append_value(buffer, static_cast<double>(2 * (last - first)), count_type, format,
                             swap);
                for (std::size_t c = first; c < last; ++c) {
                    const std::int32_t t = mesh.corner_uvs[c];
                    const std::array<double, 2> uv = t >= 0 ? mesh.uvs[static_cast<std::size_t>(t)]
                                                            : std::array<double, 2>{0.0, 0.0};
                    append_value(buffer, uv[0], PlyScalar::float32, format, swap);
                    append_value(buffer, uv[1], PlyScalar::float32, format, swap);
                }
            }
            for (std::size_t a = 0; a < face_types.size(); ++a) {
                append_value(buffer, mesh.face_attributes[a].values[f], face_types[a], format,
                             swap);
            }
            trim_first_space(at);
            end_record();
        }
        out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    });
}

}  // namespace pliant::io
