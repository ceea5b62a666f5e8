// Generated meshes: the standard scenes' sheets and the BVH benchmark's folded workload.
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

}  // namespace pliant::geometry
