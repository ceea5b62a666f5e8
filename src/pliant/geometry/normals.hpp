// Area-weighted vertex normals of a triangle mesh, for smooth shading (the mesh rasterizer's
// previews and the viewer's OpenGL drawing use the same normals).
//
//   n_v = normalize(Σ_{t ∋ v} (b − a) × (c − a)),   t = (a, b, c) counter-clockwise,
//
// the cross product being twice the triangle's area times its unit normal, so large triangles
// weigh more. A vertex whose sum vanishes (no triangle, only degenerate ones, or opposite
// triangles cancelling) gets the zero vector: callers fall back to a face normal.
// Preconditions (not checked: callers validate meshes once): every index in [0, #V), finite
// positions. The scatter is serial in triangle order and the normalization parallel by index,
// so results are bitwise identical for any number of threads. O(V + T).
#pragma once

#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::geometry {

// normals is resized to #V. sums: scratch (#V, kept by callers that run every frame).
void vertex_normals(std::span<const Vec3d> positions, std::span<const Triangle> triangles,
                    std::vector<Vec3f>& normals, std::vector<Vec3d>& sums);

inline std::vector<Vec3f> vertex_normals(std::span<const Vec3d> positions,
                                         std::span<const Triangle> triangles) {
    std::vector<Vec3f> normals;
    std::vector<Vec3d> sums;
    vertex_normals(positions, triangles, normals, sums);
    return normals;
}

}  // namespace pliant::geometry
