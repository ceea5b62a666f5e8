// Stanford PLY garments: polygons of any size with texture coordinates and the file's simple
// vertex and face properties, read into the PolygonMesh of obj_polygons.hpp so that a PLY garment
// is simulated (triangulate()) and written back like an OBJ one.
//
//   const PolygonMesh garment = read_ply_polygons("shirt.ply");
//   const geometry::TriangleMeshD mesh = triangulate(garment);  // to simulate
//   write_ply_polygons("frame_0001.ply", garment, simulated_positions);
//
// read_ply_polygons(path) reads `format ascii 1.0`, `binary_little_endian 1.0` and
// `binary_big_endian 1.0` (header grammar and scalar types as io/ply.hpp):
//   - element `vertex` (at most 2^31 - 1): scalar x, y, z (required); texture coordinates from
//     the first scalar pair present of (s, t), (u, v), (texture_u, texture_v),
//     (texture_s, texture_t) (each vertex's UV then serves all its corners); normals nx, ny, nz
//     (kept in `normals`, never used: frames get normals recomputed); every other scalar
//     property kept in vertex_attributes; list properties skipped.
//   - element `face` (optional): a list `vertex_indices` or `vertex_index` of integers, one polygon
//     of n >= 3 distinct vertices per record; an optional list `texcoord` of 2n reals (u, v per
//     corner, MeshLab's per-corner UVs; it takes precedence over vertex UVs); every other scalar
//     property kept in face_attributes; other lists skipped.
//   - other elements are skipped; `comment` and `obj_info` lines ignored.
// Throws IoError "<path>: [line <n>: ]<what>, expected <x>, got <y>" for a missing or unreadable
// file, anything read_ply refuses (header, counts the data cannot hold, truncated or trailing
// data, values outside their type, NaN/Inf coordinates, indices outside [0, #V)), a polygon with
// fewer than 3 corners or repeating a vertex, a NaN/Inf texture coordinate, a texcoord list whose
// length is not twice the corners, and more than 2^31 - 1 corners in all. The line is given for
// ASCII data. Cost: one read of the file, O(file size) decoding; peak memory the file plus the
// mesh.
//
// write_ply_polygons(path, mesh, positions, format) writes mesh with `positions` (#V, e.g. a
// simulated frame) in place of its own: `element vertex` with double x, y, z, float nx, ny, nz
// (area-weighted over the triangulation of `positions`, geometry/normals.hpp), float s, t when
// each vertex has one UV for all its corners (the layout Blender and MeshLab import), then the
// vertex attributes with their types; `element face` with `list uchar int vertex_indices` (`list
// int int` when a polygon has more than 255 corners), `list uchar float texcoord` when some vertex
// has several UVs (per-corner UVs: MeshLab reads them, Blender 3.4's importer drops them; corners
// without a UV get (0, 0)), then the face attributes. Binary formats read back bit for bit for
// positions; ASCII prints doubles with 17 and floats with 9 significant digits. The file is
// replaced atomically (atomic_file.hpp). InvalidInput (before touching the file) when positions
// has another size or a non-finite value, or an attribute has the wrong number of values, an
// unknown type or a value its type cannot hold; IoError when the file cannot be written.
#pragma once

#include <filesystem>
#include <span>

#include "pliant/core/vec3.hpp"
#include "pliant/io/obj_polygons.hpp"
#include "pliant/io/ply.hpp"

namespace pliant::io {

PolygonMesh read_ply_polygons(const std::filesystem::path& path);

void write_ply_polygons(const std::filesystem::path& path, const PolygonMesh& mesh,
                        std::span<const Vec3d> positions,
                        PlyFormat format = PlyFormat::binary_little_endian);

}  // namespace pliant::io
