// TriangleMesh: the owning representation of a triangle mesh, one std::vector per attribute.
// positions: #V points (world units, metres in scenes); triangles: #T index triples into positions,
// counter-clockwise seen from the side the normal points to.
//
// Simulation state is float (TriangleMesh). Files are read at full precision (TriangleMeshD) so
// that exact queries on double data (collision oracles, CCD) see the file's own numbers.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::geometry {

using Triangle = std::array<std::int32_t, 3>;
using Edge = std::array<std::int32_t, 2>;

template <typename Real>
struct BasicTriangleMesh {
    std::vector<Vec3<Real>> positions;  // #V
    std::vector<Triangle> triangles;    // #T

    std::size_t num_vertices() const { return positions.size(); }
    std::size_t num_triangles() const { return triangles.size(); }
};

using TriangleMesh = BasicTriangleMesh<float>;
using TriangleMeshD = BasicTriangleMesh<double>;

// Converts the positions' precision (rounding to nearest for double → float).
template <typename To, typename From>
BasicTriangleMesh<To> convert_precision(const BasicTriangleMesh<From>& mesh) {
    BasicTriangleMesh<To> out;
    out.positions.reserve(mesh.positions.size());
    for (const Vec3<From>& p : mesh.positions) {
        out.positions.push_back(vec3_cast<To>(p));
    }
    out.triangles = mesh.triangles;
    return out;
}

}  // namespace pliant::geometry
