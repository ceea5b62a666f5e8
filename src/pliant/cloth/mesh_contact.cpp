#include "pliant/cloth/mesh_contact.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace pliant::cloth {
namespace {

Vec3d barycentric_point(std::span<const Vec3d> positions, const geometry::Triangle& tri,
                        const Vec3d& b) {
    return positions[static_cast<std::size_t>(tri[0])] * b.x +
           positions[static_cast<std::size_t>(tri[1])] * b.y +
           positions[static_cast<std::size_t>(tri[2])] * b.z;
}

}  // namespace

MeshContact resolve_mesh_contact(const MovingMeshObstacle& obstacle, Vec3d& x, const Vec3d& start,
                                 double thickness, double h, double max_settle, double max_push,
                                 double extra_depth) {
    MeshContact contact;
    const MeshObstacle& mesh = *obstacle.mesh;
    const Pose& pose = obstacle.state.pose;
    const Pose& previous_pose = obstacle.state.previous_pose;
    const std::span<const Vec3d> now = mesh.mesh().positions;
    const std::span<const Vec3d> before = mesh.previous_positions();
    const Vec3d x_rest0 = pose.apply_inverse(x);
    const Vec3d start_rest = previous_pose.apply_inverse(start);
    Vec3d x_rest = x_rest0;
    std::int32_t triangle = -1;
    Vec3d barycentric{};
    Vec3d normal{};

    // Step 1: swept contact.
    if (const std::optional<MeshObstacle::SweptHit> hit = mesh.sweep(start_rest, x_rest)) {
        const Vec3d n = mesh.face_normals()[static_cast<std::size_t>(hit->triangle)];
        if (squared_norm(n) > 0.0) {
            const geometry::Triangle& tri =
                mesh.mesh().triangles[static_cast<std::size_t>(hit->triangle)];
            x_rest = barycentric_point(now, tri, hit->barycentric) + n * thickness;
            triangle = hit->triangle;
            barycentric = hit->barycentric;
            normal = n;
            contact.swept = true;
        }
    }

    // Step 2: push out of the surface at the substep's end.
    const Vec3d rigid_move = obstacle.state.surface_displacement(x);
    const double max_depth = norm(x_rest0 - start_rest) + norm(rigid_move) +
                             mesh.max_vertex_step() + 2.0 * thickness + extra_depth;
    if (const std::optional<MeshObstacle::SurfacePoint> point =
            mesh.surface_point(x_rest, std::max(thickness, max_depth))) {
        const double depth = thickness - point->surface.distance;
        if (depth > 0.0 && point->surface.distance >= -max_depth) {
            x_rest += point->surface.normal * depth;
            triangle = point->triangle;
            barycentric = point->barycentric;
            normal = point->surface.normal;
        }
    }
    if (triangle < 0) {
        return contact;
    }

    // Step 3: bounds on the correction.
    const Vec3d correction = x_rest - x_rest0;
    const double length = norm(correction);
    if (!(length > 0.0)) {
        return contact;
    }
    const geometry::Triangle& tri = mesh.mesh().triangles[static_cast<std::size_t>(triangle)];
    const Vec3d p_start = barycentric_point(before, tri, barycentric);
    const double was_in = thickness - dot(start_rest - p_start, normal);
    double settled = std::clamp(was_in, 0.0, length);
    const double excess_settle = settled > max_settle ? settled - max_settle : 0.0;
    settled -= excess_settle;
    const double allowed = norm(x_rest0 - start_rest) + thickness + max_push;
    const double excess_push = std::max(0.0, length - excess_settle - settled - allowed);
    const double excess = excess_settle + excess_push;
    if (excess > 0.0) {
        x_rest -= correction * (excess / length);
    }
    x = pose.apply(x_rest);
    contact.depth = length - excess;
    contact.settled = settled;
    contact.normal = pose.rotation.apply(normal);
    contact.lag = excess_push;
    const Vec3d p_end = barycentric_point(now, tri, barycentric);
    contact.surface_velocity = (pose.apply(p_end) - previous_pose.apply(p_start)) * (1.0 / h);
    return contact;
}

}  // namespace pliant::cloth
