// Generated meshes: the standard scenes' sheets, the BVH benchmark's folded workload, and
// obstacle shapes (sphere, box, plane square) for previews.
#pragma once

#include <cstdint>
#include <span>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::geometry {

// A flat rectangular sheet of nx × ny quads, each split into two triangles (diagonals alternate
// like a checkerboard so the mesh has no preferred direction), centred at the origin in the z = 0
// plane. width along x, height along y (world units). (nx+1)(ny+1) vertices, 2·nx·ny triangles,
// normals +z. Throws InvalidInput for nx, ny < 1 or non-positive sizes.
TriangleMesh make_grid_sheet(int nx, int ny, float width, float height);

// The number of quads per side of the square sheet whose triangle count 2n² is nearest to
// `triangles` (ties to the smaller). E.g. 2,244 → 33, 27,030 → 116, 35,992 → 134.
int nearest_square_sheet(std::int64_t triangles);

// Folds a sheet made by make_grid_sheet like an accordion, isometrically: along x the sheet runs
// in straight panels of length `panel`, joined by half-cylinder folds of diameter `gap`, so that
// consecutive layers lie `gap` apart along z. Points keep their arc length along x; y is kept.
void fold_accordion(std::span<Vec3f> positions, float panel, float gap);

// Obstacle shapes as triangle meshes (double precision, like the cloth obstacles), for previews.
// Closed shapes are edge-manifold (every edge has exactly two triangles) and oriented outwards
// (counter-clockwise seen from outside). All throw InvalidInput for non-finite arguments.

// A UV sphere: `segments` slices around +z (≥ 3, ≤ 4096) and max(2, segments / 2) stacks from
// pole to pole, the poles single vertices, every vertex at distance `radius` (> 0) from `center`.
// 2 + (stacks − 1)·segments vertices, 2·segments·(stacks − 1) triangles.
TriangleMeshD make_uv_sphere(Vec3d center, double radius, int segments);

// The axis-aligned box [min, max] (min < max on every axis): 8 corners, 12 triangles.
TriangleMeshD make_box(Vec3d min, Vec3d max);

// The square of the plane through `point` with normal `normal` (nonzero, need not be unit),
// centred at `point`, extending half_size (> 0) along two orthonormal in-plane directions:
// 4 vertices, 2 triangles facing `normal` (counter-clockwise seen from the side it points to).
TriangleMeshD make_plane_square(Vec3d point, Vec3d normal, double half_size);

}  // namespace pliant::geometry
