#include "clip_transform.hpp"

#include <gtest/gtest.h>

#include <array>
#include <random>

#include "pliant/core/error.hpp"

namespace pliant::viewer {
namespace {

// clip = M · (p, 1) for a column-major M.
std::array<double, 4> apply(const Matrix4& m, const Vec3d& p) {
    std::array<double, 4> out{};
    for (int row = 0; row < 4; ++row) {
        out[static_cast<std::size_t>(row)] =
            m[static_cast<std::size_t>(row)] * p.x + m[static_cast<std::size_t>(4 + row)] * p.y +
            m[static_cast<std::size_t>(8 + row)] * p.z + m[static_cast<std::size_t>(12 + row)];
    }
    return out;
}

// OpenGL's viewport mapping, then image rows counted downwards, must give Camera::project.
void expect_matches_project(const render::Camera& camera, double near, double far) {
    const Matrix4 m = clip_from_world(camera, near, far);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int k = 0; k < 200; ++k) {
        const Vec3d p = camera.target() + Vec3d{u(rng), u(rng), u(rng)} * 2.0;
        const render::PixelPoint expected = camera.project(p);
        if (!(expected.depth > near && expected.depth < far)) {
            continue;
        }
        const std::array<double, 4> c = apply(m, p);
        const double x = (c[0] / c[3] + 1.0) * 0.5 * camera.width();
        const double y_up = (c[1] / c[3] + 1.0) * 0.5 * camera.height();
        EXPECT_NEAR(x, expected.x, 0.01) << "point " << k;  // pixels (float matrix)
        EXPECT_NEAR(camera.height() - y_up, expected.y, 0.01);
        const double z = c[2] / c[3];
        EXPECT_GT(z, -1.0 - 1e-5);
        EXPECT_LT(z, 1.0 + 1e-5);
    }
    // The depth range's ends.
    const Vec3d at_near = camera.eye() + camera.forward() * near;
    const Vec3d at_far = camera.eye() + camera.forward() * far;
    const std::array<double, 4> cn = apply(m, at_near), cf = apply(m, at_far);
    EXPECT_NEAR(cn[2] / cn[3], -1.0, 1e-4);
    EXPECT_NEAR(cf[2] / cf[3], 1.0, 1e-4);
}

TEST(ClipTransform, ReproducesCameraProjection) {
    const render::Camera perspective = render::Camera::perspective(
        {4.0, -3.0, 2.0}, {0.5, 0.25, 0.0}, {0.0, 0.0, 1.0}, 35.0, 640, 360);
    expect_matches_project(perspective, 0.5, 20.0);
    const render::Camera orthographic = render::Camera::orthographic(
        {4.0, -3.0, 2.0}, {0.5, 0.25, 0.0}, {0.0, 0.0, 1.0}, 3.0, 300, 500);
    expect_matches_project(orthographic, 0.0, 12.0);
}

TEST(ClipTransform, DepthRangeHoldsTheSphere) {
    const render::Camera camera = render::Camera::perspective({0.0, -10.0, 0.0}, {0.0, 0.0, 0.0},
                                                              {0.0, 0.0, 1.0}, 30.0, 100, 100);
    const DepthRange range = depth_range(camera, {0.0, 0.0, 0.0}, 2.0);
    EXPECT_NEAR(range.near, 8.0, 1e-12);
    EXPECT_NEAR(range.far, 12.0, 1e-12);
    // A camera inside the sphere: near stays positive, at far / max_ratio.
    const DepthRange inside = depth_range(camera, {0.0, -10.0, 0.0}, 5.0, 1e3);
    EXPECT_NEAR(inside.far, 5.0, 1e-12);
    EXPECT_NEAR(inside.near, 5e-3, 1e-12);
}

TEST(ClipTransform, RejectsBadRanges) {
    const render::Camera camera = render::Camera::perspective({0.0, -10.0, 0.0}, {0.0, 0.0, 0.0},
                                                              {0.0, 0.0, 1.0}, 30.0, 100, 100);
    EXPECT_THROW(clip_from_world(camera, 0.0, 1.0), InvalidInput);
    EXPECT_THROW(clip_from_world(camera, 2.0, 1.0), InvalidInput);
    EXPECT_NO_THROW(clip_from_world(camera, 0.1, 1.0));
}

}  // namespace
}  // namespace pliant::viewer
