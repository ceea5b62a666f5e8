#include "picking.hpp"

#include <cmath>
#include <limits>

namespace pliant::viewer {

TriangleHit intersect_triangles(const render::Ray& ray, std::span<const Vec3d> positions,
                                std::span<const geometry::Triangle> triangles) {
    TriangleHit best;
    best.t = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < triangles.size(); ++k) {
        const geometry::Triangle& tri = triangles[k];
        const Vec3d& a = positions[static_cast<std::size_t>(tri[0])];
        const Vec3d e1 = positions[static_cast<std::size_t>(tri[1])] - a;
        const Vec3d e2 = positions[static_cast<std::size_t>(tri[2])] - a;
        const Vec3d p = cross(ray.direction, e2);
        const double det = dot(e1, p);
        if (!(std::fabs(det) > 1e-300)) {
            continue;  // parallel to the ray, or degenerate
        }
        const double inv = 1.0 / det;
        const Vec3d s = ray.origin - a;
        const double u = dot(s, p) * inv;
        if (!(u >= 0.0 && u <= 1.0)) {
            continue;
        }
        const Vec3d q = cross(s, e1);
        const double v = dot(ray.direction, q) * inv;
        if (!(v >= 0.0 && u + v <= 1.0)) {
            continue;
        }
        const double t = dot(e2, q) * inv;
        if (t >= 0.0 && t < best.t) {
            best = {static_cast<std::int32_t>(k), t, u, v};
        }
    }
    if (best.triangle < 0) {
        best.t = 0.0;
    }
    return best;
}

std::int32_t nearest_corner(const TriangleHit& hit, std::span<const geometry::Triangle> triangles) {
    if (hit.triangle < 0) {
        return -1;
    }
    const double w[3] = {1.0 - hit.u - hit.v, hit.u, hit.v};
    int corner = 0;
    for (int c = 1; c < 3; ++c) {
        if (w[c] > w[corner]) {
            corner = c;
        }
    }
    return triangles[static_cast<std::size_t>(hit.triangle)][static_cast<std::size_t>(corner)];
}

std::int32_t pick_point(const render::Camera& camera, std::span<const Vec3f> points, double x,
                        double y, double radius_pixels,
                        const std::optional<render::ClipPlane>& clip) {
    std::int32_t best = -1;
    double best_depth = std::numeric_limits<double>::infinity();
    const double r2 = radius_pixels * radius_pixels;
    for (std::size_t v = 0; v < points.size(); ++v) {
        const Vec3d p = vec3_cast<double>(points[v]);
        if (clip && dot(p - clip->point, clip->normal) < 0.0) {
            continue;
        }
        const render::PixelPoint pixel = camera.project(p);
        if (!(pixel.depth > 0.0) || pixel.depth >= best_depth) {
            continue;
        }
        const double dx = pixel.x - x, dy = pixel.y - y;
        if (dx * dx + dy * dy <= r2) {
            best = static_cast<std::int32_t>(v);
            best_depth = pixel.depth;
        }
    }
    return best;
}

Vec3d drag_target(const render::Camera& camera, double x, double y, const Vec3d& anchor) {
    const render::Ray ray = camera.ray(x, y);
    const Vec3d n = camera.forward();
    const double along = dot(ray.direction, n);  // > 0 for every pixel ray
    const double t = dot(anchor - ray.origin, n) / along;
    return ray.origin + ray.direction * t;
}

}  // namespace pliant::viewer
