#include "pliant/io/vtu.hpp"

#include <fmt/format.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <string>
#include <vector>

#include "pliant/core/error.hpp"
#include "pliant/io/atomic_file.hpp"

namespace pliant::io {

namespace {

constexpr std::uint8_t VTK_TETRA = 10;

// RFC 4648 base64 with padding.
std::string base64(const std::vector<std::uint8_t>& bytes) {
    static constexpr char ALPHABET[] =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((bytes.size() + 2) / 3 * 4);
    std::size_t i = 0;
    for (; i + 2 < bytes.size(); i += 3) {
        const std::uint32_t v =
            (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
        out += ALPHABET[(v >> 18) & 63];
        out += ALPHABET[(v >> 12) & 63];
        out += ALPHABET[(v >> 6) & 63];
        out += ALPHABET[v & 63];
    }
    if (i + 1 == bytes.size()) {
        const std::uint32_t v = std::uint32_t{bytes[i]} << 16;
        out += ALPHABET[(v >> 18) & 63];
        out += ALPHABET[(v >> 12) & 63];
        out += "==";
    } else if (i + 2 == bytes.size()) {
        const std::uint32_t v =
            (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8);
        out += ALPHABET[(v >> 18) & 63];
        out += ALPHABET[(v >> 12) & 63];
        out += ALPHABET[(v >> 6) & 63];
        out += '=';
    }
    return out;
}

// The bytes of a binary DataArray: a UInt64 byte count, then the values (little endian: every
// machine pliant supports).
template <typename T>
std::string encoded(const std::vector<T>& values) {
    const std::uint64_t count = values.size() * sizeof(T);
    std::vector<std::uint8_t> bytes;
    bytes.reserve(sizeof(count) + count);
    for (std::size_t b = 0; b < sizeof(count); ++b) {
        bytes.push_back(static_cast<std::uint8_t>(count >> (8 * b)));
    }
    for (const T& v : values) {
        std::array<std::uint8_t, sizeof(T)> raw{};
        std::memcpy(raw.data(), &v, sizeof(T));
        bytes.insert(bytes.end(), raw.begin(), raw.end());
    }
    return base64(bytes);
}

template <typename T>
void data_array(std::ostream& out, const char* type, const char* name, int components,
                const std::vector<T>& values) {
    out << "        <DataArray type=\"" << type << "\"";
    if (name != nullptr) {
        out << " Name=\"" << name << "\"";
    }
    out << " NumberOfComponents=\"" << components << "\" format=\"binary\">\n          "
        << encoded(values) << "\n        </DataArray>\n";
}

std::vector<float> flatten(std::span<const Vec3f> v) {
    std::vector<float> out;
    out.reserve(v.size() * 3);
    for (const Vec3f& p : v) {
        out.push_back(p.x);
        out.push_back(p.y);
        out.push_back(p.z);
    }
    return out;
}

}  // namespace

void write_vtu(const std::filesystem::path& path, std::span<const Vec3f> positions,
               std::span<const geometry::Tet> tets, std::span<const Vec3f> rest_positions) {
    const auto num_vertices = static_cast<std::int64_t>(positions.size());
    for (std::size_t t = 0; t < tets.size(); ++t) {
        for (const std::int32_t v : tets[t]) {
            if (v < 0 || v >= num_vertices) {
                throw InvalidInput(
                    fmt::format("write_vtu: {}: tet {} has vertex index {}, expected 0 to {}",
                                path.string(), t, v, num_vertices - 1));
            }
        }
    }
    if (!rest_positions.empty() && rest_positions.size() != positions.size()) {
        throw InvalidInput(
            fmt::format("write_vtu: {}: {} rest positions for {} positions, expected as many",
                        path.string(), rest_positions.size(), positions.size()));
    }

    std::vector<std::int64_t> connectivity;
    std::vector<std::int64_t> offsets;
    connectivity.reserve(tets.size() * 4);
    offsets.reserve(tets.size());
    for (const geometry::Tet& t : tets) {
        connectivity.insert(connectivity.end(), t.begin(), t.end());
        offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
    }
    const std::vector<std::uint8_t> types(tets.size(), VTK_TETRA);

    write_file_atomically(path, [&](std::ostream& out) {
        out << "<?xml version=\"1.0\"?>\n"
               "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
               "header_type=\"UInt64\">\n"
               "  <UnstructuredGrid>\n"
            << "    <Piece NumberOfPoints=\"" << positions.size() << "\" NumberOfCells=\""
            << tets.size() << "\">\n";
        if (!rest_positions.empty()) {
            std::vector<Vec3f> displacement(positions.size());
            for (std::size_t v = 0; v < positions.size(); ++v) {
                displacement[v] = positions[v] - rest_positions[v];
            }
            out << "      <PointData Vectors=\"displacement\">\n";
            data_array(out, "Float32", "displacement", 3, flatten(displacement));
            data_array(out, "Float32", "rest_position", 3, flatten(rest_positions));
            out << "      </PointData>\n";
            std::vector<float> ratio(tets.size());
            for (std::size_t t = 0; t < tets.size(); ++t) {
                const auto& q = tets[t];
                const auto at = [](std::span<const Vec3f> p, std::int32_t i) {
                    return vec3_cast<double>(p[static_cast<std::size_t>(i)]);
                };
                const double now =
                    geometry::signed_volume(at(positions, q[0]), at(positions, q[1]),
                                            at(positions, q[2]), at(positions, q[3]));
                const double rest =
                    geometry::signed_volume(at(rest_positions, q[0]), at(rest_positions, q[1]),
                                            at(rest_positions, q[2]), at(rest_positions, q[3]));
                ratio[t] = rest != 0.0 ? static_cast<float>(now / rest) : 0.0F;
            }
            out << "      <CellData Scalars=\"volume_ratio\">\n";
            data_array(out, "Float32", "volume_ratio", 1, ratio);
            out << "      </CellData>\n";
        }
        out << "      <Points>\n";
        data_array(out, "Float32", "Points", 3, flatten(positions));
        out << "      </Points>\n      <Cells>\n";
        data_array(out, "Int64", "connectivity", 1, connectivity);
        data_array(out, "Int64", "offsets", 1, offsets);
        data_array(out, "UInt8", "types", 1, types);
        out << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
    });
}

}  // namespace pliant::io
