#include "clip_transform.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "pliant/core/error.hpp"

namespace pliant::viewer {

Matrix4 clip_from_world(const render::Camera& camera, double near, double far) {
    const bool perspective = camera.projection() == render::Projection::perspective;
    if (!std::isfinite(near) || !std::isfinite(far) || !(near < far) ||
        (perspective && !(near > 0.0))) {
        throw InvalidInput(fmt::format(
            "viewer: depth range near {} far {}, expected finite values with {}near < far", near,
            far, perspective ? "0 < " : ""));
    }
    // Camera coordinates (x right, y up, depth along forward) as rows of the view transform.
    const Vec3d r = camera.right(), u = camera.up(), f = camera.forward(), e = camera.eye();
    const double view[3][4] = {{r.x, r.y, r.z, -dot(r, e)},
                               {u.x, u.y, u.z, -dot(u, e)},
                               {f.x, f.y, f.z, -dot(f, e)}};  // depth, positive in front
    // Pixels: x = W/2 + focal · x_cam / depth (perspective) → ndc.x = 2 focal x_cam / (W depth).
    const double sx = 2.0 * camera.focal_pixels() / camera.width();
    const double sy = 2.0 * camera.focal_pixels() / camera.height();
    double rows[4][4] = {};
    for (int c = 0; c < 4; ++c) {
        rows[0][c] = sx * view[0][c];
        rows[1][c] = sy * view[1][c];
        if (perspective) {
            // ndc.z = (a · depth + b) / depth: −1 at near, +1 at far; clip.w = depth.
            const double a = (far + near) / (far - near);
            const double b = -2.0 * far * near / (far - near);
            rows[2][c] = a * view[2][c] + (c == 3 ? b : 0.0);
            rows[3][c] = view[2][c];
        } else {
            // ndc.z = (2 depth − far − near) / (far − near); clip.w = 1.
            const double a = 2.0 / (far - near);
            rows[2][c] = a * view[2][c] + (c == 3 ? -(far + near) / (far - near) : 0.0);
            rows[3][c] = c == 3 ? 1.0 : 0.0;
        }
    }
    Matrix4 m{};
    for (int row = 0; row < 4; ++row) {
        for (int c = 0; c < 4; ++c) {
            m[4 * static_cast<std::size_t>(c) + static_cast<std::size_t>(row)] =
                static_cast<float>(rows[row][c]);
        }
    }
    return m;
}

DepthRange depth_range(const render::Camera& camera, const Vec3d& centre, double radius,
                       double max_ratio) {
    const double d = dot(centre - camera.eye(), camera.forward());
    const double r = std::max(radius, 1e-9 * std::max(1.0, std::fabs(d)));
    if (camera.projection() == render::Projection::orthographic) {
        return {d - r, d + r};
    }
    const double far = std::max(d + r, 1e-6);
    return {std::max(d - r, far / max_ratio), far};
}

}  // namespace pliant::viewer
