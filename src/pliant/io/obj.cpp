#include "pliant/io/obj.hpp"

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/validate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {

namespace {

// What the validating scan learns from the text.
struct ObjScan {
    std::vector<Vec3d> positions;
    std::uint64_t num_triangles = 0;  // sum of (n - 2) over the faces
};

// Validates the `v` and `f` lines and reads the coordinates at double precision. Lines end at
// \n, \r\n or \r, and a line is a `v` / `f` line when it starts (after spaces and tabs) with
// "v" / "f" and a space or tab: the same rules as tinyobjloader, so both see the same vertices.
ObjScan scan_obj(std::string_view text, const std::filesystem::path& path) {
    ObjScan scan;
    std::size_t line_number = 0;
    const auto fail = [&](std::string_view message) {
        throw IoError(fmt::format("{}: line {}: {}", path.string(), line_number, message));
    };
    std::int64_t max_index = 0;  // the largest positive vertex index, 1-based
    std::size_t max_index_line = 0;
    std::vector<std::string_view> tokens;

    std::size_t pos = 0;
    while (pos < text.size()) {
        std::size_t end = pos;
        while (end < text.size() && text[end] != '\n' && text[end] != '\r') {
            ++end;
        }
        std::size_t next = end + 1;
        if (end == text.size()) {
            next = end;
        } else if (text[end] == '\r' && next < text.size() && text[next] == '\n') {
            ++next;
        }
        std::string_view line = text.substr(pos, end - pos);
        pos = next;
        ++line_number;
        // OBJ is text: a NUL or another control byte means a binary file under an .obj name.
        for (std::size_t k = 0; k < line.size(); ++k) {
            const auto byte = static_cast<unsigned char>(line[k]);
            if (byte < 0x20 && byte != '\t' && byte != '\f' && byte != '\v') {
                fail(fmt::format("not a text OBJ file: byte 0x{:02x} in column {}", byte, k + 1));
            }
        }
        while (!line.empty() && detail::is_blank(line.front())) {
            line.remove_prefix(1);
        }
        if (line.size() < 2 || !detail::is_blank(line[1])) {
            continue;
        }

        if (line[0] == 'v') {
            detail::split_blank_tokens(line.substr(2), tokens);
            if (tokens.size() < 3) {
                fail(fmt::format("vertex {} has {} coordinates, expected 3 (x y z)",
                                 scan.positions.size() + 1, tokens.size()));
            }
            Vec3d p;
            for (int axis = 0; axis < 3; ++axis) {
                double value = 0.0;
                const detail::ParseStatus status = detail::parse_real(tokens[axis], value);
                if (status != detail::ParseStatus::ok || !std::isfinite(value)) {
                    fail(fmt::format("vertex {} coordinate {}: expected a finite number, got {}",
                                     scan.positions.size() + 1, "xyz"[axis],
                                     detail::quote(tokens[axis])));
                }
                p[axis] = value;
            }
            scan.positions.push_back(p);
        } else if (line[0] == 'f') {
            detail::split_blank_tokens(line.substr(2), tokens);
            if (tokens.size() < 3) {
                fail(fmt::format("face has {} vertices, expected at least 3", tokens.size()));
            }
            const auto num_vertices = static_cast<std::int64_t>(scan.positions.size());
            for (const std::string_view token : tokens) {
                const std::string_view vertex = token.substr(0, token.find('/'));
                std::int64_t index = 0;
                const detail::ParseStatus status = detail::parse_integer(vertex, index);
                if (status != detail::ParseStatus::ok || index == 0 ||
                    index > std::numeric_limits<std::int32_t>::max()) {
                    fail(
                        fmt::format("bad face vertex {}, expected a 1-based vertex index (or a "
                                    "negative one relative to the last vertex), got {}",
                                    detail::quote(token), detail::quote(vertex)));
                }
                if (index < 0 && num_vertices + index < 0) {
                    fail(
                        fmt::format("face vertex index {} reaches before the first vertex, "
                                    "expected -{} <= index <= -1 (vertices so far: {})",
                                    index, num_vertices, num_vertices));
                }
                if (index > max_index) {
                    max_index = index;
                    max_index_line = line_number;
                }
            }
            scan.num_triangles += tokens.size() - 2;
        }
    }

    const auto num_vertices = static_cast<std::int64_t>(scan.positions.size());
    if (max_index > num_vertices) {
        line_number = max_index_line;
        fail(
            fmt::format("face vertex index {} is out of range, expected 1 <= index <= {} (the "
                        "number of vertices)",
                        max_index, num_vertices));
    }
    return scan;
}

std::string trim_trailing_newlines(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) {
        text.pop_back();
    }
    for (char& c : text) {
        if (c == '\n') {
            c = ' ';
        }
    }
    return text;
}

template <typename Real>
void write_obj_impl(const std::filesystem::path& path,
                    const geometry::BasicTriangleMesh<Real>& mesh) {
    geometry::validate_mesh(mesh, path.string());
    write_file_atomically(path, [&](std::ostream& out) {
        constexpr std::size_t FLUSH_BYTES = std::size_t{1} << 20;
        fmt::memory_buffer buffer;
        const auto flush_if_full = [&](bool force) {
            if (force || buffer.size() >= FLUSH_BYTES) {
                out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                buffer.clear();
            }
        };
        fmt::format_to(std::back_inserter(buffer),
                       "# written by pliant: {} vertices, {} triangles\n", mesh.num_vertices(),
                       mesh.num_triangles());
        // The shortest text that reads back to the same float or double (fmt's "{}").
        for (const Vec3<Real>& p : mesh.positions) {
            fmt::format_to(std::back_inserter(buffer), "v {} {} {}\n", p.x, p.y, p.z);
            flush_if_full(false);
        }
        for (const geometry::Triangle& t : mesh.triangles) {
            fmt::format_to(std::back_inserter(buffer), "f {} {} {}\n", t[0] + 1, t[1] + 1,
                           t[2] + 1);
            flush_if_full(false);
        }
        flush_if_full(true);
    });
}

}  // namespace

geometry::TriangleMeshD read_obj(const std::filesystem::path& path) {
    // Step 1: one read, then pliant's validating scan (coordinates, index ranges, line numbers).
    const std::string text = read_file(path);
    ObjScan scan = scan_obj(text, path);

    // Step 2: tinyobjloader parses the faces and triangulates them. Parsing from the string keeps
    // it from opening material files.
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    tinyobj::ObjReader reader;
    if (!reader.ParseFromString(text, "", config)) {
        throw IoError(fmt::format("{}: tinyobjloader: {}", path.string(),
                                  trim_trailing_newlines(reader.Error())));
    }
    const std::size_t num_vertices = scan.positions.size();
    if (reader.GetAttrib().vertices.size() != 3 * num_vertices) {
        throw IoError(
            fmt::format("{}: tinyobjloader read {} vertices, expected {} (the number of 'v' lines)",
                        path.string(), reader.GetAttrib().vertices.size() / 3, num_vertices));
    }

    // Step 3: collect the triangles. tinyobjloader skips faces it cannot use with only a
    // warning, so the indices and the triangle count are checked against the scan.
    geometry::TriangleMeshD mesh;
    mesh.positions = std::move(scan.positions);
    mesh.triangles.reserve(static_cast<std::size_t>(scan.num_triangles));
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const std::vector<tinyobj::index_t>& indices = shape.mesh.indices;
        for (std::size_t i = 0; i + 2 < indices.size(); i += 3) {
            geometry::Triangle t{};
            for (std::size_t k = 0; k < 3; ++k) {
                const int v = indices[i + k].vertex_index;
                if (v < 0 || static_cast<std::size_t>(v) >= num_vertices) {
                    throw IoError(fmt::format(
                        "{}: triangle {} has vertex index {}, expected 1 <= index <= {}",
                        path.string(), mesh.triangles.size(), v + 1, num_vertices));
                }
                t[k] = v;
            }
            mesh.triangles.push_back(t);
        }
    }
    if (mesh.triangles.size() != scan.num_triangles) {
        throw IoError(fmt::format(
            "{}: tinyobjloader triangulated the faces into {} triangles, expected {} (n - 2 per "
            "face of n vertices){}",
            path.string(), mesh.triangles.size(), scan.num_triangles,
            reader.Warning().empty() ? "" : "; " + trim_trailing_newlines(reader.Warning())));
    }

    try {
        geometry::validate_mesh(mesh, path.string());
    } catch (const InvalidInput& e) {
        throw IoError(e.what());
    }
    return mesh;
}

void write_obj(const std::filesystem::path& path, const geometry::TriangleMesh& mesh) {
    write_obj_impl(path, mesh);
}

void write_obj(const std::filesystem::path& path, const geometry::TriangleMeshD& mesh) {
    write_obj_impl(path, mesh);
}

}  // namespace pliant::io
