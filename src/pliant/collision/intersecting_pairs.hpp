// Intersecting triangle pairs of a triangle mesh: an exact certificate that a frame has no
// self-intersection; and of two meshes: that cloth does not pass through an obstacle's surface.
//
//   const std::int64_t n = count_intersecting_pairs(positions, triangles);  // 0: no intersection
//   const std::int64_t m = count_intersecting_pairs(cloth_positions, cloth_triangles,
//                                                   body_positions, body_triangles);
//
// Counts the unordered pairs {i, j}, i ≠ j, of triangles that share no vertex index and whose
// closed point sets intersect (touching at a point counts), decided exactly by
// geometry::triangles_intersect: no false negative and no false positive from rounding.
// Triangles that share a vertex are never counted, even when they also overlap elsewhere (a fold
// through a shared vertex is not reported); degenerate (zero-area) triangles are tested as the
// segments or points they are.
//
// Method: float boxes of the triangles, rounded outward from the double coordinates
// (outward_float), so that no pair overlapping in double is lost; an LBVH over them and its self
// traversal (bvh/traversal.hpp) give the candidate pairs; pairs sharing a vertex are dropped,
// the rest confirmed on the exact double boxes and then tested exactly. Parallel over the
// traversal's fixed chunks; the count and the sorted list are identical for any number of threads.
// O(T) for boxes and the LBVH build, then the traversal and one exact test per candidate pair
// (most end after 6 orient3d; exactly coplanar pairs, as in a flat sheet, take the predicates'
// exact path). Measured in bench/ (docs/performance.md).
//
// Two meshes A and B: the pairs (i, j) of triangle i of A and triangle j of B whose closed point
// sets intersect, by the same exact test; no pair is excluded (the meshes share no vertex). An
// LBVH over each mesh and their pair traversal give the candidates; the count is the same for any
// number of threads.
//
// positions: #V points (world units); triangles: #T index triples into positions.
// Throws InvalidInput naming the offending element when an index is out of [0, #V), a triangle
// repeats a vertex index, or a coordinate is NaN, infinite or outside the exact domain of
// geometry/exact_predicates.hpp (nonzero with |x| < 2^-300 ≈ 4.9e-91 or |x| > 2^300 ≈ 2.0e90).
// Float positions are converted to double exactly (every float is in the exact domain). Keeps no
// state between calls; concurrent calls are safe.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::collision {

// Number of intersecting pairs of triangles that share no vertex.
std::int64_t count_intersecting_pairs(std::span<const Vec3d> positions,
                                      std::span<const geometry::Triangle> triangles);
std::int64_t count_intersecting_pairs(std::span<const Vec3f> positions,
                                      std::span<const geometry::Triangle> triangles);

// Number of intersecting pairs (triangle of A, triangle of B). InvalidInput as above, naming the
// mesh ("a" or "b").
std::int64_t count_intersecting_pairs(std::span<const Vec3d> positions_a,
                                      std::span<const geometry::Triangle> triangles_a,
                                      std::span<const Vec3d> positions_b,
                                      std::span<const geometry::Triangle> triangles_b);

// The same pairs as triangle indices {i, j} with i < j, sorted lexicographically.
std::vector<std::array<std::int32_t, 2>> find_intersecting_pairs(
    std::span<const Vec3d> positions, std::span<const geometry::Triangle> triangles);
std::vector<std::array<std::int32_t, 2>> find_intersecting_pairs(
    std::span<const Vec3f> positions, std::span<const geometry::Triangle> triangles);

}  // namespace pliant::collision
