// The OpenGL transform of a render::Camera: the 4 × 4 matrix from world to clip coordinates
// whose viewport mapping reproduces Camera::project exactly (up to float rounding), so that
// OpenGL draws what the library's rasterizer and ray caster see.
//
// With clip = M · (p, 1) and ndc = clip.xyz / clip.w, a viewport of width × height pixels puts p
// at window x = (ndc.x + 1) W / 2 and window y (upwards) = (ndc.y + 1) H / 2, that is at image
// pixel (x, H − y_window) = Camera::project(p) (image rows counted downwards, glReadPixels rows
// upwards). Depth: ndc.z = −1 at distance `near` and +1 at `far` along the view direction
// (perspective: hyperbolic in depth, orthographic: linear).
//
// Column-major (OpenGL's layout, glUniformMatrix4fv with transpose = GL_FALSE). No GL calls.
#pragma once

#include <array>

#include "pliant/core/vec3.hpp"
#include "pliant/render/camera.hpp"

namespace pliant::viewer {

using Matrix4 = std::array<float, 16>;  // column-major: element (row r, column c) at [4c + r]

// InvalidInput unless 0 < near < far (perspective) or near < far (orthographic), both finite.
Matrix4 clip_from_world(const render::Camera& camera, double near, double far);

// near and far distances along the view direction that hold a sphere (centre, radius) in front
// of the camera: [max(d − r, max_ratio⁻¹ · (d + r)), d + r] with d the sphere centre's depth,
// so that depth precision stays within max_ratio (perspective). Orthographic: [d − r, d + r].
struct DepthRange {
    double near;
    double far;
};
DepthRange depth_range(const render::Camera& camera, const Vec3d& centre, double radius,
                       double max_ratio = 1e4);

}  // namespace pliant::viewer
