// Stanford PLY (polygon file format) for triangle meshes, with pliant's own codec.
//
// read_ply(path) reads `format ascii 1.0`, `binary_little_endian 1.0` and `binary_big_endian 1.0`:
//   - element `vertex` (at most 2^31 - 1 records: indices are int32) with scalar properties
//     x, y, z of any PLY scalar type (char uchar short ushort int uint float double, or int8
//     uint8 int16 uint16 int32 uint32 float32 float64), converted exactly to double (a float
//     property gives the float's value). Other vertex properties, scalar or list, are skipped.
//   - element `face` (optional; no faces gives an empty triangle list) with a list property named
//     `vertex_indices` or `vertex_index` of integer count and index types. A polygon of n >= 3
//     vertices becomes the fan (v0, vi, vi+1), i = 1 … n-2. Other face properties are skipped.
//   - any other element (edge, material, …) is skipped; `comment` and `obj_info` lines are
//     ignored.
// ASCII data is read one record per line (blank lines allowed). Binary data must end exactly after
// the last element.
// Returns #V positions (file order) and #T triangles (face order, fans in corner order).
// Throws IoError "<path>: [line <n>: ]<what is wrong>, expected <x>, got <y>" for a missing or
// unreadable file, a file that is not PLY, a malformed or truncated header or data section, an
// unknown format or type, element counts the data cannot hold (checked before allocating), a
// face with fewer than 3 vertices, a vertex index outside [0, #V), a triangle repeating a vertex,
// and a NaN/Inf coordinate. The line number is given for ASCII data.
// Cost: one bulk read of the file, then O(file size) decoding from memory; peak memory is the
// file plus the mesh.
//
// write_ply(path, mesh, format) writes `element vertex` with `property float` (TriangleMesh) or
// `property double` (TriangleMeshD) x, y, z and `element face` with `property list uchar int
// vertex_indices`. ASCII prints floats with 9 and doubles with 17 significant digits, so every
// format reads back bit for bit. The file is replaced atomically (see atomic_file.hpp).
// Throws InvalidInput (before touching the file) when the mesh fails geometry::validate_mesh,
// and IoError "<path>: …" when the file cannot be written.
//
// write_point_cloud_ply(path, positions, colors, format) writes points only: `element vertex` with
// `property float` x, y, z and, when `colors` is not empty, `property uchar` red, green, blue (the
// layout of COLMAP's and nerfstudio's sparse point files); no face element. `colors` is empty or
// has one RGB triple per position (InvalidInput otherwise, or for a NaN/Inf position, before
// touching the file). read_ply reads the positions back.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::io {

enum class PlyFormat { ascii, binary_little_endian, binary_big_endian };

// The header keyword of a format: "ascii", "binary_little_endian", "binary_big_endian".
const char* to_string(PlyFormat format);

geometry::TriangleMeshD read_ply(const std::filesystem::path& path);

void write_ply(const std::filesystem::path& path, const geometry::TriangleMesh& mesh,
               PlyFormat format = PlyFormat::binary_little_endian);
void write_ply(const std::filesystem::path& path, const geometry::TriangleMeshD& mesh,
               PlyFormat format = PlyFormat::binary_little_endian);

void write_point_cloud_ply(const std::filesystem::path& path, std::span<const Vec3f> positions,
                           std::span<const std::array<std::uint8_t, 3>> colors,
                           PlyFormat format = PlyFormat::binary_little_endian);

}  // namespace pliant::io
