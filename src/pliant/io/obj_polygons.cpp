#include "pliant/io/obj_polygons.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/geometry/normals.hpp"
#include "pliant/geometry/validate.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {
namespace {

constexpr std::int64_t MAX_ELEMENTS = std::numeric_limits<std::int32_t>::max();

std::string_view trim_spaces(std::string_view s) {
    while (!s.empty() && (detail::is_blank(s.front()) || s.front() == '\f' || s.front() == '\v')) {
        s.remove_prefix(1);
    }
    while (!s.empty() && (detail::is_blank(s.back()) || s.back() == '\f' || s.back() == '\v')) {
        s.remove_suffix(1);
    }
    return s;
}

class Parser {
public:
    Parser(std::string_view text, const std::filesystem::path& path) : m_text(text), m_path(path) {}

    PolygonMesh parse() {
        std::size_t pos = 0;
        while (pos < m_text.size()) {
            std::size_t end = pos;
            while (end < m_text.size() && m_text[end] != '\n' && m_text[end] != '\r') {
                ++end;
            }
            std::size_t next = end + 1;
            if (end == m_text.size()) {
                next = end;
            } else if (m_text[end] == '\r' && next < m_text.size() && m_text[next] == '\n') {
                ++next;
            }
            ++m_line;
            statement(m_text.substr(pos, end - pos));
            pos = next;
        }
        check_forward_references();
        return std::move(m_mesh);
    }

private:
    [[noreturn]] void fail(const std::string& message) const {
        throw IoError(fmt::format("{}: line {}: {}", m_path.string(), m_line, message));
    }

    double number(std::string_view token, const char* what) const {
        double x = 0.0;
        if (detail::parse_real(token, x) != detail::ParseStatus::ok || !std::isfinite(x)) {
            fail(fmt::format("{}: expected a finite number, got {}", what, detail::quote(token)));
        }
        return x;
    }

    std::int32_t intern(std::string_view text) {
        const std::string key(text);
        const auto it = m_names.find(key);
        if (it != m_names.end()) {
            return it->second;
        }
        const auto index = static_cast<std::int32_t>(m_mesh.names.size());
        m_mesh.names.push_back(key);
        m_names.emplace(key, index);
        return index;
    }

    void check_count(std::size_t size, const char* what) const {
        if (static_cast<std::int64_t>(size) >= MAX_ELEMENTS) {
            fail(fmt::format("more than 2^31 - 1 {}", what));
        }
    }

    // A 1-based or negative index into `count` elements defined so far → 0-based. Positive indices
    // may refer forward (checked at the end of the file).
    std::int32_t index(std::string_view token, std::size_t count, const char* what) {
        std::int64_t i = 0;
        if (detail::parse_integer(token, i) != detail::ParseStatus::ok) {
            fail(fmt::format("face corner: {} index: expected an integer, got {}", what,
                             detail::quote(token)));
        }
        if (i == 0 || i > MAX_ELEMENTS || i < -static_cast<std::int64_t>(count)) {
            fail(fmt::format("face corner: {} index {}: expected 1 <= index or -{} <= index <= -1",
                             what, i, count));
        }
        const std::int64_t zero_based = i > 0 ? i - 1 : static_cast<std::int64_t>(count) + i;
        return static_cast<std::int32_t>(zero_based);
    }

    void corner(std::string_view token) {
        std::string_view parts[3];
        int n = 0;
        std::size_t start = 0;
        for (std::size_t i = 0; i <= token.size(); ++i) {
            if (i == token.size() || token[i] == '/') {
                if (n == 3) {
                    fail(fmt::format("face corner {}: expected v, v/vt, v//vn or v/vt/vn",
                                     detail::quote(token)));
                }
                parts[n++] = token.substr(start, i - start);
                start = i + 1;
            }
        }
        if (parts[0].empty() || (n == 2 && parts[1].empty()) || (n == 3 && parts[2].empty())) {
            fail(fmt::format("face corner {}: expected v, v/vt, v//vn or v/vt/vn",
                             detail::quote(token)));
        }
        const std::int32_t v = index(parts[0], m_mesh.positions.size(), "vertex");
        m_max_vertex = std::max(m_max_vertex, v);
        std::int32_t t = -1;
        std::int32_t vn = -1;
        if (n >= 2 && !parts[1].empty()) {
            t = index(parts[1], m_mesh.uvs.size(), "texture coordinate");
            m_max_uv = std::max(m_max_uv, t);
        }
        if (n == 3) {
            vn = index(parts[2], m_mesh.normals.size(), "normal");
            m_max_normal = std::max(m_max_normal, vn);
        }
        m_mesh.corner_vertices.push_back(v);
        m_mesh.corner_uvs.push_back(t);
        m_mesh.corner_normals.push_back(vn);
    }

    void statement(std::string_view line) {
        if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
            line = line.substr(0, hash);
        }
        detail::split_blank_tokens(line, m_tokens);
        if (m_tokens.empty()) {
            return;
        }
        const std::string_view key = m_tokens[0];
        // The text after the keyword, trimmed (names may contain spaces).
        const auto rest = [&] {
            const std::size_t at = line.find(key) + key.size();
            return trim_spaces(line.substr(at));
        };
        if (key == "v") {
            if (m_tokens.size() < 4) {
                fail(fmt::format("'v' needs x y z, got {} numbers", m_tokens.size() - 1));
            }
            check_count(m_mesh.positions.size(), "vertices");
            m_mesh.positions.push_back({number(m_tokens[1], "v x"), number(m_tokens[2], "v y"),
                                        number(m_tokens[3], "v z")});
        } else if (key == "vt") {
            if (m_tokens.size() < 2) {
                fail("'vt' needs u [v [w]], got no numbers");
            }
            check_count(m_mesh.uvs.size(), "texture coordinates");
            m_mesh.uvs.push_back({number(m_tokens[1], "vt u"),
                                  m_tokens.size() > 2 ? number(m_tokens[2], "vt v") : 0.0});
        } else if (key == "vn") {
            if (m_tokens.size() < 4) {
                fail(fmt::format("'vn' needs x y z, got {} numbers", m_tokens.size() - 1));
            }
            check_count(m_mesh.normals.size(), "normals");
            m_mesh.normals.push_back({number(m_tokens[1], "vn x"), number(m_tokens[2], "vn y"),
                                      number(m_tokens[3], "vn z")});
        } else if (key == "f") {
            if (m_tokens.size() < 4) {
                fail(fmt::format("a face needs at least 3 corners, got {}", m_tokens.size() - 1));
            }
            check_count(m_mesh.corner_vertices.size() + m_tokens.size(), "face corners");
            const std::size_t first = m_mesh.corner_vertices.size();
            for (std::size_t k = 1; k < m_tokens.size(); ++k) {
                corner(m_tokens[k]);
            }
            for (std::size_t k = first; k < m_mesh.corner_vertices.size(); ++k) {
                for (std::size_t j = k + 1; j < m_mesh.corner_vertices.size(); ++j) {
                    if (m_mesh.corner_vertices[k] == m_mesh.corner_vertices[j]) {
                        fail(fmt::format(
                            "a face repeats vertex {} (corners {} and {}), expected "
                            "distinct vertices",
                            m_mesh.corner_vertices[k] + 1, k - first + 1, j - first + 1));
                    }
                }
            }
            m_mesh.face_starts.push_back(static_cast<std::int32_t>(m_mesh.corner_vertices.size()));
            m_mesh.face_tags.push_back(m_tags);
        } else if (key == "o") {
            m_tags.object = intern(rest());
        } else if (key == "g") {
            m_tags.group = intern(rest());
        } else if (key == "s") {
            m_tags.smoothing = intern(rest());
        } else if (key == "usemtl") {
            m_tags.material = intern(rest());
        } else if (key == "mtllib") {
            m_mesh.material_libraries.emplace_back(rest());
        }
        // Anything else (l, p, vp, curves, unknown statements) is ignored.
    }

    void check_forward_references() const {
        const auto check = [&](std::int32_t max, std::size_t count, const char* what) {
            if (max >= 0 && static_cast<std::size_t>(max) >= count) {
                throw IoError(
                    fmt::format("{}: face {} index {} is out of range, expected 1 <= "
                                "index <= {} (the number of {}s)",
                                m_path.string(), what, max + 1, count, what));
            }
        };
        check(m_max_vertex, m_mesh.positions.size(), "vertex");
        check(m_max_uv, m_mesh.uvs.size(), "texture coordinate");
        check(m_max_normal, m_mesh.normals.size(), "normal");
    }

    std::string_view m_text;
    const std::filesystem::path& m_path;
    std::size_t m_line = 0;
    PolygonMesh m_mesh;
    PolygonMesh::FaceTags m_tags;
    std::map<std::string, std::int32_t> m_names;
    std::vector<std::string_view> m_tokens;
    std::int32_t m_max_vertex = -1;
    std::int32_t m_max_uv = -1;
    std::int32_t m_max_normal = -1;
};

// Twice the signed area of the 2D triangle (a, b, c).
double cross2(const std::array<double, 2>& a, const std::array<double, 2>& b,
              const std::array<double, 2>& c) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Ear clipping of a simple polygon (corner indices `ring` into the face's vertices) projected onto
// the plane of its Newell normal; false when no ear is found (not simple in that plane).
bool ear_clip(const std::vector<Vec3d>& points, std::vector<std::array<int, 3>>& out) {
    const std::size_t n = points.size();
    Vec3d normal{0.0, 0.0, 0.0};
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3d& a = points[i];
        const Vec3d& b = points[(i + 1) % n];
        normal.x += (a.y - b.y) * (a.z + b.z);
        normal.y += (a.z - b.z) * (a.x + b.x);
        normal.z += (a.x - b.x) * (a.y + b.y);
    }
    if (!(norm(normal) > 0.0)) {
        return false;
    }
    // Drop the normal's largest axis: the projection keeps the winding (sign fixed below).
    const double ax = std::abs(normal.x);
    const double ay = std::abs(normal.y);
    const double az = std::abs(normal.z);
    const int drop = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
    const double sign = (drop == 0 ? normal.x : drop == 1 ? normal.y : normal.z) > 0.0 ? 1.0 : -1.0;
    std::vector<std::array<double, 2>> p(n);
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3d& q = points[i];
        p[i] = drop == 0   ? std::array<double, 2>{q.y, q.z}
               : drop == 1 ? std::array<double, 2>{q.z, q.x}
                           : std::array<double, 2>{q.x, q.y};
    }
    std::vector<int> ring(n);
    for (std::size_t i = 0; i < n; ++i) {
        ring[i] = static_cast<int>(i);
    }
    while (ring.size() > 3) {
        bool clipped = false;
        const std::size_t m = ring.size();
        for (std::size_t i = 0; i < m && !clipped; ++i) {
            const int a = ring[(i + m - 1) % m];
            const int b = ring[i];
            const int c = ring[(i + 1) % m];
            if (sign * cross2(p[a], p[b], p[c]) <= 0.0) {
                continue;  // reflex or degenerate corner
            }
            bool empty = true;
            for (const int d : ring) {
                if (d == a || d == b || d == c) {
                    continue;
                }
                if (sign * cross2(p[a], p[b], p[d]) >= 0.0 &&
                    sign * cross2(p[b], p[c], p[d]) >= 0.0 &&
                    sign * cross2(p[c], p[a], p[d]) >= 0.0) {
                    empty = false;
                    break;
                }
            }
            if (empty) {
                out.push_back({a, b, c});
                ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
                clipped = true;
            }
        }
        if (!clipped) {
            return false;
        }
    }
    out.push_back({ring[0], ring[1], ring[2]});
    return true;
}

}  // namespace

PolygonMesh read_obj_polygons(const std::filesystem::path& path) {
    const std::string text = read_file(path);
    return Parser(text, path).parse();
}

geometry::TriangleMeshD triangulate(const PolygonMesh& mesh,
                                    std::vector<std::int32_t>* face_of_triangle) {
    geometry::TriangleMeshD out;
    out.positions = mesh.positions;
    if (face_of_triangle != nullptr) {
        face_of_triangle->clear();
    }
    std::vector<Vec3d> points;
    std::vector<std::array<int, 3>> local;
    for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
        const std::int32_t* v = mesh.corner_vertices.data() + mesh.face_starts[f];
        const std::size_t n = mesh.num_corners(f);
        const auto at = [&](int k) {
            return mesh.positions[static_cast<std::size_t>(v[k])];
        };
        local.clear();
        if (n == 3) {
            local.push_back({0, 1, 2});
        } else if (n == 4) {
            if (norm(at(0) - at(2)) <= norm(at(1) - at(3))) {
                local.push_back({0, 1, 2});
                local.push_back({0, 2, 3});
            } else {
                local.push_back({0, 1, 3});
                local.push_back({1, 2, 3});
            }
        } else {
            points.clear();
            for (std::size_t k = 0; k < n; ++k) {
                points.push_back(at(static_cast<int>(k)));
            }
            if (!ear_clip(points, local)) {
                local.clear();
                for (std::size_t k = 1; k + 1 < n; ++k) {
                    local.push_back({0, static_cast<int>(k), static_cast<int>(k + 1)});
                }
            }
        }
        for (const std::array<int, 3>& t : local) {
            out.triangles.push_back({v[t[0]], v[t[1]], v[t[2]]});
            if (face_of_triangle != nullptr) {
                face_of_triangle->push_back(static_cast<std::int32_t>(f));
            }
        }
        for (std::size_t k = 0; k < n; ++k) {
            for (std::size_t j = k + 1; j < n; ++j) {
                if (v[k] == v[j]) {
                    throw InvalidInput(fmt::format(
                        "face {} repeats vertex {} (corners {} and {}): expected distinct vertices",
                        f + 1, v[k] + 1, k + 1, j + 1));
                }
            }
        }
    }
    return out;
}

void write_obj_polygons(const std::filesystem::path& path, const PolygonMesh& mesh,
                        std::span<const Vec3d> positions) {
    if (positions.size() != mesh.positions.size()) {
        throw InvalidInput(fmt::format("{}: expected {} positions (the mesh's vertices), got {}",
                                       path.string(), mesh.positions.size(), positions.size()));
    }
    geometry::validate_positions(positions, path.string());
    const bool with_normals = !mesh.normals.empty();
    std::vector<Vec3f> normals;
    if (with_normals) {
        const geometry::TriangleMeshD triangles = triangulate(mesh);
        std::vector<Vec3d> sums;
        geometry::vertex_normals(positions, triangles.triangles, normals, sums);
    }
    write_file_atomically(path, [&](std::ostream& out) {
        constexpr std::size_t FLUSH_BYTES = std::size_t{1} << 20;
        fmt::memory_buffer buffer;
        const auto flush_if_full = [&](bool force) {
            if (force || buffer.size() >= FLUSH_BYTES) {
                out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
                buffer.clear();
            }
        };
        const auto put = [&](fmt::string_view format, const auto&... args) {
            fmt::format_to(std::back_inserter(buffer), fmt::runtime(format), args...);
            flush_if_full(false);
        };
        put("# written by pliant: {} vertices, {} faces\n", positions.size(), mesh.num_faces());
        for (const std::string& library : mesh.material_libraries) {
            put("mtllib {}\n", library);
        }
        for (const Vec3d& p : positions) {
            put("v {} {} {}\n", p.x, p.y, p.z);
        }
        for (const std::array<double, 2>& t : mesh.uvs) {
            put("vt {} {}\n", t[0], t[1]);
        }
        for (const Vec3f& n : normals) {
            put("vn {} {} {}\n", n.x, n.y, n.z);
        }
        PolygonMesh::FaceTags current;
        const auto tag = [&](std::int32_t now, std::int32_t& was, const char* keyword) {
            if (now != was && now >= 0) {
                put("{} {}\n", keyword, mesh.names[static_cast<std::size_t>(now)]);
            }
            was = now;
        };
        for (std::size_t f = 0; f < mesh.num_faces(); ++f) {
            const PolygonMesh::FaceTags& tags = mesh.face_tags[f];
            tag(tags.object, current.object, "o");
            tag(tags.group, current.group, "g");
            tag(tags.smoothing, current.smoothing, "s");
            tag(tags.material, current.material, "usemtl");
            put("f");
            for (auto c = static_cast<std::size_t>(mesh.face_starts[f]);
                 c < static_cast<std::size_t>(mesh.face_starts[f + 1]); ++c) {
                const std::int32_t v = mesh.corner_vertices[c] + 1;
                const std::int32_t t = mesh.corner_uvs[c] + 1;
                if (with_normals) {
                    put(t > 0 ? " {0}/{1}/{0}" : " {0}//{0}", v, t);
                } else {
                    put(t > 0 ? " {}/{}" : " {}", v, t);
                }
            }
            put("\n");
        }
        flush_if_full(true);
    });
}

}  // namespace pliant::io
