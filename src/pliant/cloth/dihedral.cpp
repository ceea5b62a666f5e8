#include "pliant/cloth/dihedral.hpp"

#include <cmath>

namespace pliant::cloth {

DihedralAngle dihedral_angle(const Vec3d& x0, const Vec3d& x1, const Vec3d& x2, const Vec3d& x3) {
    const Vec3d e = x3 - x2;
    const Vec3d n_a = cross(x2 - x0, x3 - x0);
    const Vec3d n_b = cross(x3 - x1, x2 - x1);
    const double length_e = norm(e);
    const double area2_a = squared_norm(n_a);
    const double area2_b = squared_norm(n_b);
    DihedralAngle result{0.0, {}, false};
    if (!(length_e > 0.0) || !(area2_a > 0.0) || !(area2_b > 0.0)) {
        return result;
    }
    const Vec3d unit_a = n_a * (1.0 / std::sqrt(area2_a));
    const Vec3d unit_b = n_b * (1.0 / std::sqrt(area2_b));
    const Vec3d unit_e = e * (1.0 / length_e);
    result.angle = std::atan2(dot(cross(unit_a, unit_b), unit_e), dot(unit_a, unit_b));
    const Vec3d scaled_a = n_a * (1.0 / area2_a);
    const Vec3d scaled_b = n_b * (1.0 / area2_b);
    result.gradient[0] = scaled_a * (-length_e);
    result.gradient[1] = scaled_b * (-length_e);
    result.gradient[2] =
        scaled_a * (-dot(x0 - x3, e) / length_e) - scaled_b * (dot(x1 - x3, e) / length_e);
    result.gradient[3] =
        scaled_a * (dot(x0 - x2, e) / length_e) + scaled_b * (dot(x1 - x2, e) / length_e);
    result.is_valid = true;
    return result;
}

double dihedral_angle_value(const Vec3d& x0, const Vec3d& x1, const Vec3d& x2, const Vec3d& x3) {
    return dihedral_angle(x0, x1, x2, x3).angle;
}

}  // namespace pliant::cloth
