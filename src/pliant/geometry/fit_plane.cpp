#include "pliant/geometry/fit_plane.hpp"

namespace pliant::geometry {

std::optional<FittedPlane> fit_plane(std::span<const Vec3d> positions,
                                     std::span<const Triangle> triangles,
                                     std::span<const std::int32_t> subset, double min_agreement) {
    Vec3d normal_sum{0.0, 0.0, 0.0};
    Vec3d centroid_sum{0.0, 0.0, 0.0};
    double area_sum = 0.0;
    for (const std::int32_t o : subset) {
        const Triangle& t = triangles[static_cast<std::size_t>(o)];
        const Vec3d& a = positions[static_cast<std::size_t>(t[0])];
        const Vec3d& b = positions[static_cast<std::size_t>(t[1])];
        const Vec3d& c = positions[static_cast<std::size_t>(t[2])];
        const Vec3d n = cross(b - a, c - a);
        const double area = norm(n);
        normal_sum += n;
        centroid_sum += (a + b + c) * (area / 3.0);
        area_sum += area;
    }
    const double length = norm(normal_sum);
    if (!(area_sum > 0.0) || !(length >= min_agreement * area_sum) || !(length > 0.0)) {
        return std::nullopt;
    }
    return FittedPlane{centroid_sum * (1.0 / area_sum), normal_sum * (1.0 / length)};
}

}  // namespace pliant::geometry
