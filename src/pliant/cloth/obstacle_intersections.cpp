#include "pliant/cloth/obstacle_intersections.hpp"

#include <array>
#include <variant>
#include <vector>

#include "pliant/cloth/mesh_obstacle.hpp"
#include "pliant/collision/intersecting_pairs.hpp"
#include "pliant/collision/point_triangle.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/geometry/triangle_intersection.hpp"

namespace pliant::cloth {
namespace {

constexpr std::int64_t TRIANGLE_GRAIN = 1 << 12;

bool in_closed_box(const BoxObstacle& box, const Vec3d& p) {
    return p.x >= box.min.x && p.y >= box.min.y && p.z >= box.min.z && p.x <= box.max.x &&
           p.y <= box.max.y && p.z <= box.max.z;
}

bool reaches_into_box(const BoxObstacle& box, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
    if (in_closed_box(box, a) || in_closed_box(box, b) || in_closed_box(box, c)) {
        return true;
    }
    // No corner inside: the triangle meets the closed box only through its surface.
    const auto corner = [&](int k) {
        return Vec3d{(k & 1) != 0 ? box.max.x : box.min.x, (k & 2) != 0 ? box.max.y : box.min.y,
                     (k & 4) != 0 ? box.max.z : box.min.z};
    };
    // The six faces, each as two triangles of its corners (k with one bit fixed).
    static constexpr std::array<std::array<int, 4>, 6> FACES = {
        {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}}};
    for (const std::array<int, 4>& face : FACES) {
        const Vec3d p0 = corner(face[0]);
        const Vec3d p1 = corner(face[1]);
        const Vec3d p2 = corner(face[2]);
        const Vec3d p3 = corner(face[3]);
        if (geometry::triangles_intersect(a, b, c, p0, p1, p2) ||
            geometry::triangles_intersect(a, b, c, p0, p2, p3)) {
            return true;
        }
    }
    return false;
}

}  // namespace

bool triangle_reaches_into(const Obstacle& obstacle, const Vec3d& a, const Vec3d& b,
                           const Vec3d& c) {
    if (const auto* plane = std::get_if<PlaneObstacle>(&obstacle)) {
        const auto behind = [&](const Vec3d& p) {
            return dot(p - plane->point, plane->normal) <= 0.0;
        };
        return behind(a) || behind(b) || behind(c);
    }
    if (const auto* sphere = std::get_if<SphereObstacle>(&obstacle)) {
        return collision::point_triangle_proximity(sphere->center, a, b, c).distance <=
               sphere->radius;
    }
    return reaches_into_box(std::get<BoxObstacle>(obstacle), a, b, c);
}

std::int32_t obstacle_met_by(const ClothModel& model, const Vec3d& a, const Vec3d& b,
                             const Vec3d& c) {
    const std::span<const MovingMeshObstacle> meshes = model.mesh_obstacles();
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        const Pose& pose = meshes[k].state.pose;
        if (meshes[k].mesh->meets_triangle(pose.apply_inverse(a), pose.apply_inverse(b),
                                           pose.apply_inverse(c))) {
            return static_cast<std::int32_t>(k);
        }
    }
    const std::span<const MovingObstacle> obstacles = model.obstacles();
    for (std::size_t k = 0; k < obstacles.size(); ++k) {
        if (triangle_reaches_into(obstacles[k].current, a, b, c)) {
            return static_cast<std::int32_t>(meshes.size() + k);
        }
    }
    return -1;
}

bool triangle_meets_obstacles(const ClothModel& model, const Vec3d& a, const Vec3d& b,
                              const Vec3d& c) {
    return obstacle_met_by(model, a, b, c) >= 0;
}

std::int64_t count_obstacle_intersections(const ClothModel& model) {
    const std::span<const Vec3d> x = model.positions();
    const std::span<const geometry::Triangle> triangles = model.triangles();
    std::int64_t total = 0;
    for (const MovingMeshObstacle& mesh : model.mesh_obstacles()) {
        const geometry::TriangleMeshD& surface = mesh.mesh->mesh();
        std::vector<Vec3d> placed(surface.positions.size());
        parallel_for(
            static_cast<std::int64_t>(placed.size()),
            [&](std::int64_t v) {
                const auto k = static_cast<std::size_t>(v);
                placed[k] = mesh.state.pose.apply(surface.positions[k]);
            },
            TRIANGLE_GRAIN);
        total += collision::count_intersecting_pairs(x, triangles, placed, surface.triangles);
    }
    for (const MovingObstacle& obstacle : model.obstacles()) {
        total += parallel_reduce(
            static_cast<std::int64_t>(triangles.size()), std::int64_t{0},
            [&](std::int64_t begin, std::int64_t end) {
                std::int64_t n = 0;
                for (std::int64_t t = begin; t < end; ++t) {
                    const geometry::Triangle& tri = triangles[static_cast<std::size_t>(t)];
                    const auto corner = [&](int k) -> const Vec3d& {
                        return x[static_cast<std::size_t>(tri[static_cast<std::size_t>(k)])];
                    };
                    n += triangle_reaches_into(obstacle.current, corner(0), corner(1), corner(2))
                             ? 1
                             : 0;
                }
                return n;
            },
            [](std::int64_t sum, std::int64_t n) { return sum + n; }, TRIANGLE_GRAIN);
    }
    return total;
}

}  // namespace pliant::cloth
