// Wavefront OBJ for triangle meshes.
//
// read_obj(path) reads `v x y z` lines (extra values such as w or a colour are ignored) and `f`
// lines (`f 1 2 3`, `f 1/4 2/5 3/6`, `f 1//7 …`, 1-based; negative indices count back from the
// last vertex defined so far). Faces are triangulated by tinyobjloader (triangulate = true:
// quads split along the shorter diagonal, larger polygons by ear clipping). Lines (`l`), points
// (`p`), normals, texture coordinates, groups and materials are ignored; `mtllib` files are not
// opened. Returns #V positions (file order) and #T triangles (file order).
// Precision: the Debian tinyobjloader is built with float, so pliant reads the coordinates
// itself in the same pass that validates them, with correctly rounded std::from_chars at double
// precision: the positions are the file's own numbers. tinyobjloader supplies the faces.
// Throws IoError "<path>: [line <n>: ]<what is wrong>, expected <x>, got <y>" for a missing or
// unreadable file, a parse error, a `v` line with fewer than 3 numbers, a NaN/Inf coordinate, a
// face with fewer than 3 vertices, a vertex index 0 or outside the vertices, and a triangle that
// repeats a vertex (geometry::validate_mesh).
// Cost: one bulk read; the text is scanned twice (validation, tinyobjloader).
//
// write_obj(path, mesh) writes `v x y z` (each number the shortest text that reads back to the
// same float, or double, bit for bit) and `f a b c` (1-based). The file is replaced atomically (see
// atomic_file.hpp). Throws InvalidInput (before touching the file) when the mesh fails
// geometry::validate_mesh, and IoError "<path>: …" when the file cannot be written.
#pragma once

#include <filesystem>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::io {

geometry::TriangleMeshD read_obj(const std::filesystem::path& path);

void write_obj(const std::filesystem::path& path, const geometry::TriangleMesh& mesh);
void write_obj(const std::filesystem::path& path, const geometry::TriangleMeshD& mesh);

}  // namespace pliant::io
