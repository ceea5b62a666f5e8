#include "pliant/cloth/isometric_bending.hpp"

#include <cmath>

#include "pliant/cloth/dihedral.hpp"

namespace pliant::cloth {

std::optional<std::array<double, 4>> isometric_bending_stencil(const Vec3d& x0, const Vec3d& x1,
                                                               const Vec3d& x2, const Vec3d& x3) {
    const Vec3d e = x3 - x2;
    const double length = norm(e);
    const double area_a = norm(cross(x2 - x0, x3 - x0));  // twice the area
    const double area_b = norm(cross(x3 - x1, x2 - x1));
    if (!(length > 0.0) || !(area_a > 0.0) || !(area_b > 0.0) || !std::isfinite(length) ||
        !std::isfinite(area_a) || !std::isfinite(area_b)) {
        return std::nullopt;
    }
    if (!(std::abs(dihedral_angle_value(x0, x1, x2, x3)) <= ISOMETRIC_FLAT_ANGLE)) {
        return std::nullopt;
    }
    const Vec3d axis = e * (1.0 / length);
    const double k0 = length / area_a;
    const double k1 = length / area_b;
    const double k3 = -(k0 * dot(x0 - x2, axis) + k1 * dot(x1 - x2, axis)) / length;
    const double k2 = -(k0 + k1 + k3);
    return std::array<double, 4>{k0, k1, k2, k3};
}

Vec3d isometric_bending_vector(const std::array<double, 4>& stencil, const Vec3d& x0,
                               const Vec3d& x1, const Vec3d& x2, const Vec3d& x3) {
    return (x0 - x2) * stencil[0] + (x1 - x2) * stencil[1] + (x3 - x2) * stencil[3];
}

}  // namespace pliant::cloth
