#include "pliant/io/tetgen.hpp"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"
#include "pliant/io/detail/text.hpp"
#include "pliant/io/read_file.hpp"

namespace pliant::io {
namespace {

// The non-empty lines of a TetGen file, split into tokens with comments removed, each with its
// 1-based line number for messages.
class TokenLines {
public:
    explicit TokenLines(std::filesystem::path path)
        : m_path(std::move(path)), m_text(read_file(m_path)) {}

    // Advances to the next line holding a token; false at the end of the file.
    bool next() {
        while (m_pos < m_text.size()) {
            std::size_t end = m_pos;
            while (end < m_text.size() && m_text[end] != '\n' && m_text[end] != '\r') {
                ++end;
            }
            std::string_view line(m_text.data() + m_pos, end - m_pos);
            ++m_line;
            if (end < m_text.size() && m_text[end] == '\r' && end + 1 < m_text.size() &&
                m_text[end + 1] == '\n') {
                ++end;
            }
            m_pos = end + 1;
            if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) {
                line = line.substr(0, hash);
            }
            m_tokens.clear();
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
                    m_tokens.push_back(line.substr(start, i - start));
                }
            }
            if (!m_tokens.empty()) {
                return true;
            }
        }
        return false;
    }

    std::size_t size() const { return m_tokens.size(); }
    std::size_t text_size() const { return m_text.size(); }

    template <typename... Args>
    [[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) const {
        throw IoError(fmt::format("{}: line {}: {}", m_path.string(), m_line,
                                  fmt::format(format, std::forward<Args>(args)...)));
    }
    [[noreturn]] void fail_at_end(std::string_view what) const {
        throw IoError(fmt::format("{}: {}", m_path.string(), what));
    }

    // Token `i` of the current line as an integer in [lo, hi].
    std::int64_t integer(std::size_t i, std::string_view what, std::int64_t lo,
                         std::int64_t hi) const {
        if (i >= m_tokens.size()) {
            fail("missing {}, expected {} numbers on the line, got {}", what, i + 1,
                 m_tokens.size());
        }
        std::int64_t value = 0;
        if (detail::parse_integer(m_tokens[i], value) != detail::ParseStatus::ok) {
            fail("{} is {}, expected an integer", what, detail::quote(m_tokens[i]));
        }
        if (value < lo || value > hi) {
            if (lo == hi) {
                fail("{} is {}, expected {}", what, value, lo);
            }
            fail("{} is {}, expected {} to {}", what, value, lo, hi);
        }
        return value;
    }

    double real(std::size_t i, std::string_view what) const {
        if (i >= m_tokens.size()) {
            fail("missing {}, expected {} numbers on the line, got {}", what, i + 1,
                 m_tokens.size());
        }
        double value = 0.0;
        const detail::ParseStatus status = detail::parse_real(m_tokens[i], value);
        if (status != detail::ParseStatus::ok || !std::isfinite(value)) {
            fail("{} is {}, expected a finite number", what, detail::quote(m_tokens[i]));
        }
        return value;
    }

    // The record count of a header: at most what the file could hold (≥ 2 bytes per record) and
    // what 32-bit indices can address.
    std::int64_t count(std::string_view what) const {
        const std::int64_t most = std::min<std::int64_t>(
            std::numeric_limits<std::int32_t>::max(), static_cast<std::int64_t>(m_text.size() / 2));
        return integer(0, what, 0, most);
    }

private:
    std::filesystem::path m_path;
    std::string m_text;
    std::size_t m_pos = 0;
    std::size_t m_line = 0;
    std::vector<std::string_view> m_tokens;
};

struct Nodes {
    std::vector<Vec3d> positions;
    std::int64_t base = 0;  // index of the first point (0 or 1)
};

Nodes read_nodes(const std::filesystem::path& path) {
    TokenLines lines(path);
    if (!lines.next()) {
        lines.fail_at_end("empty file, expected the header '<#points> 3 <#attributes> <0|1>'");
    }
    const std::int64_t count = lines.count("point count");
    lines.integer(1, "dimension", 3, 3);
    const std::int64_t attributes =
        lines.size() > 2 ? lines.integer(2, "attribute count", 0, 1000) : 0;
    const std::int64_t markers =
        lines.size() > 3 ? lines.integer(3, "boundary marker count", 0, 1) : 0;
    Nodes nodes;
    nodes.positions.reserve(static_cast<std::size_t>(count));
    for (std::int64_t p = 0; p < count; ++p) {
        if (!lines.next()) {
            lines.fail_at_end(fmt::format("the file ends after {} points, expected {}", p, count));
        }
        if (p == 0) {
            nodes.base = lines.integer(0, "first point index", 0, 1);
        } else {
            lines.integer(0, "point index", nodes.base + p, nodes.base + p);
        }
        const std::size_t expected = static_cast<std::size_t>(4 + attributes + markers);
        if (lines.size() != expected) {
            lines.fail(
                "point has {} numbers, expected {} (index, x, y, z, {} attributes, {} "
                "markers)",
                lines.size(), expected, attributes, markers);
        }
        nodes.positions.push_back({lines.real(1, "x"), lines.real(2, "y"), lines.real(3, "z")});
    }
    if (lines.next()) {
        lines.fail("data after the {} declared points", count);
    }
    return nodes;
}

}  // namespace

geometry::TetMesh read_tetgen(const std::filesystem::path& path) {
    std::filesystem::path base = path;
    if (path.extension() == ".node" || path.extension() == ".ele") {
        base.replace_extension();
    }
    const Nodes nodes = read_nodes(std::filesystem::path(base.string() + ".node"));
    const auto num_points = static_cast<std::int64_t>(nodes.positions.size());

    TokenLines lines(std::filesystem::path(base.string() + ".ele"));
    if (!lines.next()) {
        lines.fail_at_end("empty file, expected the header '<#tets> <4|10> <0|1>'");
    }
    const std::int64_t count = lines.count("tet count");
    const std::int64_t nodes_per_tet = lines.integer(1, "nodes per tet", 4, 10);
    if (nodes_per_tet != 4 && nodes_per_tet != 10) {
        lines.fail("nodes per tet is {}, expected 4 or 10", nodes_per_tet);
    }
    const std::int64_t regions =
        lines.size() > 2 ? lines.integer(2, "region attribute count", 0, 1) : 0;

    geometry::TetMesh mesh;
    mesh.positions.reserve(nodes.positions.size());
    for (const Vec3d& p : nodes.positions) {
        mesh.positions.push_back(vec3_cast<float>(p));
    }
    mesh.tets.reserve(static_cast<std::size_t>(count));
    std::int64_t tet_base = 0;
    for (std::int64_t t = 0; t < count; ++t) {
        if (!lines.next()) {
            lines.fail_at_end(fmt::format("the file ends after {} tets, expected {}", t, count));
        }
        if (t == 0) {
            tet_base = lines.integer(0, "first tet index", 0, 1);
        } else {
            lines.integer(0, "tet index", tet_base + t, tet_base + t);
        }
        const std::size_t expected = static_cast<std::size_t>(1 + nodes_per_tet + regions);
        if (lines.size() != expected) {
            lines.fail("tet has {} numbers, expected {} (index, {} nodes, {} region attributes)",
                       lines.size(), expected, nodes_per_tet, regions);
        }
        geometry::Tet tet{};
        for (std::size_t c = 0; c < 4; ++c) {
            tet[c] = static_cast<std::int32_t>(
                lines.integer(1 + c, "node index", nodes.base, nodes.base + num_points - 1) -
                nodes.base);
            for (std::size_t d = 0; d < c; ++d) {
                if (tet[d] == tet[c]) {
                    lines.fail("tet repeats node {}, expected 4 distinct nodes",
                               tet[c] + nodes.base);
                }
            }
        }
        const auto p = [&](std::size_t c) {
            return nodes.positions[static_cast<std::size_t>(tet[c])];
        };
        const double volume = geometry::signed_volume(p(0), p(1), p(2), p(3));
        if (volume == 0.0) {
            lines.fail(
                "tet has zero volume (its 4 nodes are coplanar), expected a positive volume");
        }
        if (volume < 0.0) {
            std::swap(tet[2], tet[3]);
        }
        mesh.tets.push_back(tet);
    }
    if (lines.next()) {
        lines.fail("data after the {} declared tets", count);
    }
    return mesh;
}

void write_tetgen(const std::filesystem::path& base, const geometry::TetMesh& mesh) {
    const auto num_vertices = static_cast<std::int64_t>(mesh.positions.size());
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
        const Vec3f& p = mesh.positions[v];
        if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
            throw InvalidInput(fmt::format("write_tetgen: vertex {} is not finite", v));
        }
    }
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
        for (const std::int32_t i : mesh.tets[t]) {
            if (i < 0 || i >= num_vertices) {
                throw InvalidInput(fmt::format("write_tetgen: tet {} has node {}, expected 0 to {}",
                                               t, i, num_vertices - 1));
            }
        }
    }
    write_file_atomically(std::filesystem::path(base.string() + ".node"), [&](std::ostream& out) {
        out << fmt::format("{} 3 0 0\n", mesh.positions.size());
        for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
            const Vec3f& p = mesh.positions[v];
            out << fmt::format("{} {:.9g} {:.9g} {:.9g}\n", v, p.x, p.y, p.z);
        }
    });
    write_file_atomically(std::filesystem::path(base.string() + ".ele"), [&](std::ostream& out) {
        out << fmt::format("{} 4 0\n", mesh.tets.size());
        for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
            const geometry::Tet& k = mesh.tets[t];
            out << fmt::format("{} {} {} {} {}\n", t, k[0], k[1], k[2], k[3]);
        }
    });
}

}  // namespace pliant::io
