// Mesh files by extension: `.obj` (obj.hpp) and `.ply` (ply.hpp), case-insensitive.
//
// read_mesh(path) → read_obj or read_ply; positions at the file's full precision. Wherever a mesh
// is required (every command that reads one): a file without triangles (empty, only vertices, or
// faces that are all lines or points) is InvalidInput "<path>: expected a mesh with at least one
// triangle, got N vertices and no triangles".
// write_mesh(path, mesh) → write_obj or write_ply (binary little-endian), replacing the file
// atomically. Both throw IoError "<path>: unsupported mesh file extension '<ext>', expected one
// of .obj, .ply" for any other extension (checked before touching the file), and whatever the
// format's reader or writer throws.
#pragma once

#include <filesystem>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::io {

geometry::TriangleMeshD read_mesh(const std::filesystem::path& path);

void write_mesh(const std::filesystem::path& path, const geometry::TriangleMesh& mesh);
void write_mesh(const std::filesystem::path& path, const geometry::TriangleMeshD& mesh);

}  // namespace pliant::io
