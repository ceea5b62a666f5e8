// Validation of mesh data at module entry points. Throws InvalidInput naming the first offending
// element and both values: an index out of [0, #V), a NaN/Inf coordinate, a triangle that repeats
// a vertex. `what` prefixes the message (a file name or an argument name).
#pragma once

#include <span>
#include <string_view>

#include "pliant/geometry/triangle_mesh.hpp"

namespace pliant::geometry {

void validate_positions(std::span<const Vec3f> positions, std::string_view what);
void validate_positions(std::span<const Vec3d> positions, std::string_view what);
void validate_triangles(std::span<const Triangle> triangles, std::size_t num_vertices,
                        std::string_view what);

template <typename Real>
void validate_mesh(const BasicTriangleMesh<Real>& mesh, std::string_view what) {
    validate_positions(std::span<const Vec3<Real>>(mesh.positions), what);
    validate_triangles(mesh.triangles, mesh.positions.size(), what);
}

}  // namespace pliant::geometry
