#include "pliant/cloth/obstacles.hpp"

#include <algorithm>
#include <cmath>

namespace pliant::cloth {
namespace {

SurfaceDistance plane_distance(const PlaneObstacle& plane, const Vec3d& x) {
    const Vec3d n = plane.normal * (1.0 / norm(plane.normal));
    return {dot(x - plane.point, n), n};
}

SurfaceDistance sphere_distance(const SphereObstacle& sphere, const Vec3d& x) {
    const Vec3d d = x - sphere.center;
    const double length = norm(d);
    if (!(length > 0.0)) {
        return {-sphere.radius, Vec3d{0.0, 0.0, 1.0}};
    }
    return {length - sphere.radius, d * (1.0 / length)};
}

SurfaceDistance box_distance(const BoxObstacle& box, const Vec3d& x) {
    const Vec3d clamped{std::clamp(x.x, box.min.x, box.max.x),
                        std::clamp(x.y, box.min.y, box.max.y),
                        std::clamp(x.z, box.min.z, box.max.z)};
    const Vec3d outside = x - clamped;
    const double length = norm(outside);
    if (length > 0.0) {
        return {length, outside * (1.0 / length)};
    }
    // Inside: the nearest face.
    const double gaps[6] = {x.x - box.min.x, box.max.x - x.x, x.y - box.min.y,
                            box.max.y - x.y, x.z - box.min.z, box.max.z - x.z};
    int nearest = 0;
    for (int k = 1; k < 6; ++k) {
        if (gaps[k] < gaps[nearest]) {
            nearest = k;
        }
    }
    Vec3d normal{0.0, 0.0, 0.0};
    const double sign = (nearest % 2 == 0) ? -1.0 : 1.0;
    (nearest / 2 == 0 ? normal.x : nearest / 2 == 1 ? normal.y : normal.z) = sign;
    return {-gaps[nearest], normal};
}

}  // namespace

SurfaceDistance surface_distance(const Obstacle& obstacle, const Vec3d& x) {
    return std::visit(
        [&](const auto& o) -> SurfaceDistance {
            using T = std::decay_t<decltype(o)>;
            if constexpr (std::is_same_v<T, PlaneObstacle>) {
                return plane_distance(o, x);
            } else if constexpr (std::is_same_v<T, SphereObstacle>) {
                return sphere_distance(o, x);
            } else {
                return box_distance(o, x);
            }
        },
        obstacle);
}

ContactCorrection push_out(const Obstacle& obstacle, Vec3d& x, double thickness) {
    // Most vertices of a sheet over a sphere are out of its reach: no square root and division.
    if (out_of_reach(obstacle, x, thickness)) {
        return {0.0, Vec3d{0.0, 0.0, 1.0}};
    }
    const SurfaceDistance surface = surface_distance(obstacle, x);
    const double depth = thickness - surface.distance;
    if (!(depth > 0.0)) {
        return {0.0, surface.normal};
    }
    x += surface.normal * depth;
    return {depth, surface.normal};
}

Vec3d apply_friction(const Vec3d& velocity, const Vec3d& normal, double normal_speed,
                     double static_friction, double kinetic_friction) {
    const Vec3d tangential = velocity - normal * dot(velocity, normal);
    const double speed = norm(tangential);
    if (speed <= static_friction * normal_speed) {
        return velocity - tangential;
    }
    return velocity - tangential * std::min(kinetic_friction * normal_speed / speed, 1.0);
}

}  // namespace pliant::cloth
