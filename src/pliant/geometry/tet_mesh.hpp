// TetMesh: the owning representation of a tetrahedral mesh, one std::vector per attribute.
// positions: #V points (world units); tets: #T index quadruples into positions, positively
// oriented: signed_volume(a, b, c, d) = (b − a) · ((c − a) × (d − a)) / 6 > 0.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::geometry {

using Tet = std::array<std::int32_t, 4>;

template <typename Real>
struct BasicTetMesh {
    std::vector<Vec3<Real>> positions;  // #V
    std::vector<Tet> tets;              // #T

    std::size_t num_vertices() const { return positions.size(); }
    std::size_t num_tets() const { return tets.size(); }
};

using TetMesh = BasicTetMesh<float>;

// Signed volume of the tetrahedron (a, b, c, d): positive when (b − a, c − a, d − a) is a
// right-handed frame. World units cubed.
template <typename T>
PLIANT_HOST_DEVICE constexpr T signed_volume(Vec3<T> a, Vec3<T> b, Vec3<T> c, Vec3<T> d) {
    return dot(b - a, cross(c - a, d - a)) / T(6);
}

}  // namespace pliant::geometry
