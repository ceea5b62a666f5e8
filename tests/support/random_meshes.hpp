// Random and structured test inputs with fixed seeds: triangle soups, jittered grids, boxes.
#pragma once

#include <cstdint>
#include <vector>

#include "pliant/core/aabb.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::test {

// n random triangles in the unit cube, each with edges of length up to `size`.
geometry::TriangleMesh random_triangle_soup(int n, float size, std::uint32_t seed);
// A grid sheet of nx × ny quads with every vertex jittered by up to `jitter` edge lengths, then
// crumpled in z by `amplitude` (world units; the sheet spans [-0.5, 0.5]²).
geometry::TriangleMesh jittered_sheet(int nx, int ny, float jitter, float amplitude,
                                      std::uint32_t seed);
// Box of each triangle.
std::vector<AABB> triangle_boxes(const geometry::TriangleMesh& mesh, float inflate = 0.0f);
// n random boxes in the unit cube with sides up to `size`.
std::vector<AABB> random_boxes(int n, float size, std::uint32_t seed);

}  // namespace pliant::test
