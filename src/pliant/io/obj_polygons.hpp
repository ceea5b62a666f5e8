// Wavefront OBJ as garment and DCC tools write it (Blender, Maya, Houdini, Marvelous Designer,
// CLO): polygons of any size with texture coordinates, normals, objects, groups, smoothing groups
// and materials, kept so that simulated frames can be written back with the input's faces.
//
//   const PolygonMesh garment = read_obj_polygons("shirt.obj");
//   std::vector<std::int32_t> face_of_triangle;
//   const geometry::TriangleMeshD mesh = triangulate(garment, &face_of_triangle);  // to simulate
//   write_obj_polygons("frame_0001.obj", garment, simulated_positions);
//
// read_obj_polygons(path) reads, in file order:
//   v x y z [...]      a position (extra values such as w or a colour are ignored);
//   vt u [v [w]]       a texture coordinate (v defaults to 0; w is dropped);
//   vn x y z           a normal;
//   f c1 c2 c3 [...]   a polygon of >= 3 corners `v`, `v/vt`, `v//vn` or `v/vt/vn` (1-based;
//                      negative indices count back from the last element defined so far);
//   o NAME, g NAMES, s GROUP, usemtl NAME   the object, group(s), smoothing group and material
//                      of the faces that follow (kept as written, after trimming);
//   mtllib FILES       material libraries (kept as written; not opened).
// Comments (`#` to the end of the line), blank lines, `l`, `p` and other statements are ignored;
// lines end at \n, \r\n or \r; a line ending in `\` is not joined with the next.
// Numbers are read with correctly rounded std::from_chars at double precision.
// Throws IoError "<path>: line <n>: <what is wrong>, expected <x>, got <y>" for a missing or
// unreadable file, a statement with too few or unparsable numbers, a NaN/Inf value, a face with
// fewer than 3 corners or repeating a vertex, a malformed corner, an index 0 or outside the
// elements it refers to and more than 2^31 - 1 elements of a kind. A file without faces gives a
// mesh without faces (callers that need a surface check num_faces()).
//
// triangulate(mesh, face_of_triangle): triangles in face order; a triangle stays; a quad is split
// along its shorter diagonal (ties: 0-2); larger polygons by ear clipping in the plane of their
// Newell normal (a fan when the polygon is not simple there). Triangles keep the polygon's
// winding. face_of_triangle (optional) gets each triangle's face. Throws InvalidInput naming the
// face when a polygon repeats a vertex (read_obj_polygons never returns one).
//
// write_obj_polygons(path, mesh, positions) writes mesh with `positions` (#V, e.g. a simulated
// frame) in place of its own: `mtllib` lines, `v` (shortest round-trip text), `vt` as read, `vn`
// per vertex recomputed from `positions` (area-weighted over the triangulation; only when the
// input had normals, each corner then refers to its vertex's normal), then the faces in order with
// `o`, `g`, `s` and `usemtl` written where they change. The file is replaced atomically (see
// atomic_file.hpp). InvalidInput (before touching the file) when positions has another size or a
// non-finite value; IoError when the file cannot be written.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::io {

struct PolygonMesh {
    std::vector<Vec3d> positions;            // `v`, #V
    std::vector<std::array<double, 2>> uvs;  // `vt`
    std::vector<Vec3d> normals;              // `vn` as read
    // Face f's corners are [face_starts[f], face_starts[f + 1]); #F + 1 entries.
    std::vector<std::int32_t> face_starts{0};
    std::vector<std::int32_t> corner_vertices;  // 0-based
    std::vector<std::int32_t> corner_uvs;       // 0-based, -1: none
    std::vector<std::int32_t> corner_normals;   // 0-based, -1: none
    // Per face, the statements in effect: indices into `names`, -1 before the first.
    struct FaceTags {
        std::int32_t object = -1;     // `o`
        std::int32_t group = -1;      // `g`
        std::int32_t smoothing = -1;  // `s`
        std::int32_t material = -1;   // `usemtl`
    };
    std::vector<FaceTags> face_tags;
    std::vector<std::string> names;               // the statements' text after the keyword
    std::vector<std::string> material_libraries;  // `mtllib` lines' text after the keyword
    // Scalar vertex and face properties of a PLY file besides its geometry (a vertex colour
    // `red`, a face `flags` …), kept to be written back by write_ply_polygons (ply_polygons.hpp);
    // empty for OBJ. `type` is the PLY type name ("uchar", "float" …); `values` holds #V (vertex)
    // or #F (face) values, each exact for its type.
    struct Attribute {
        std::string name;
        std::string type;
        std::vector<double> values;
    };
    std::vector<Attribute> vertex_attributes;
    std::vector<Attribute> face_attributes;

    std::size_t num_faces() const { return face_starts.size() - 1; }
    std::size_t num_corners(std::size_t face) const {
        return static_cast<std::size_t>(face_starts[face + 1] - face_starts[face]);
    }
};

PolygonMesh read_obj_polygons(const std::filesystem::path& path);

geometry::TriangleMeshD triangulate(const PolygonMesh& mesh,
                                    std::vector<std::int32_t>* face_of_triangle = nullptr);

void write_obj_polygons(const std::filesystem::path& path, const PolygonMesh& mesh,
                        std::span<const Vec3d> positions);

}  // namespace pliant::io
