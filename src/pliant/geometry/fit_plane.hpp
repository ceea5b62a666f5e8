// The plane of some triangles of a mesh, as untangling (cloth/untangle.hpp) moves cloth along:
// the area-weighted centroid and the direction of the summed area normals,
//
//   centre = Σ A_t c_t / Σ A_t,   normal = Σ n_t / |Σ n_t|,   n_t = (b − a) × (c − a), A_t = |n_t|,
//
// c_t the centroid of t = (a, b, c). None when the triangles have no area, or when their normals
// disagree: |Σ n_t| < min_agreement Σ |n_t|. The ratio |Σ n_t| / Σ |n_t| is 1 for triangles in
// one plane wound alike, cos(θ/2) for two equal halves whose normals are θ apart, and 0 for two
// layers of a fold wound against each other, whose summed normal would be noise.
// Preconditions (not checked): indices in range, finite positions. O(#subset), sequential.
#pragma once

#include <cstdint>
#include <optional>
#include <span>

#include "pliant/core/vec3.hpp"
#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::geometry {

struct FittedPlane {
    Vec3d centre;  // a point of the plane, m
    Vec3d normal;  // unit
};

// The plane of triangles[subset[k]] (min_agreement in [0, 1]).
std::optional<FittedPlane> fit_plane(std::span<const Vec3d> positions,
                                     std::span<const Triangle> triangles,
                                     std::span<const std::int32_t> subset, double min_agreement);

}  // namespace pliant::geometry
