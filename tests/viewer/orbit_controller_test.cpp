#include "orbit_controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pliant/core/error.hpp"
#include "pliant/render/camera.hpp"

namespace pliant::viewer {
namespace {

const AABBd BOX{{-1.0, -2.0, 0.0}, {3.0, 2.0, 1.5}};

void expect_same_camera(const render::Camera& a, const render::Camera& b, double tolerance) {
    EXPECT_NEAR(norm(a.eye() - b.eye()), 0.0, tolerance);
    EXPECT_NEAR(norm(a.target() - b.target()), 0.0, tolerance);
    EXPECT_NEAR(norm(a.up() - b.up()), 0.0, tolerance);
    EXPECT_EQ(a.fov_y_degrees(), b.fov_y_degrees());
    EXPECT_EQ(a.width(), b.width());
    EXPECT_EQ(a.height(), b.height());
}

// The starting view is `pliant render --camera AZ,EL,DIST`'s camera: exactly for DIST > 0, and
// the framing camera of render::frame_box for DIST = 0.
TEST(OrbitController, StartsAtTheCameraOfPliantRender) {
    const OrbitController given(BOX, 30.0, 20.0, 7.5, 640, 480);
    const render::Camera a = given.camera(640, 480);
    const render::Camera b = render::orbit_camera(BOX, 30.0, 20.0, 7.5, 640, 480);
    expect_same_camera(a, b, 0.0);
    const OrbitController framed(BOX, -60.0, 25.0, 0.0, 320, 200);
    expect_same_camera(framed.camera(320, 200), render::frame_box(BOX, -60.0, 25.0, 320, 200),
                       1e-12);
}

TEST(OrbitController, OrbitPanZoomAndReset) {
    OrbitController c(BOX, 0.0, 10.0, 10.0, 400, 300);
    c.orbit(100.0, 0.0);  // right: the eye moves clockwise seen from above
    EXPECT_NEAR(c.azimuth(), -100.0 * OrbitController::DEGREES_PER_PIXEL, 1e-12);
    c.orbit(0.0, 1e6);  // clamped away from the pole
    EXPECT_EQ(c.elevation(), OrbitController::MAX_ELEVATION);
    c.orbit(0.0, -1e6);
    EXPECT_EQ(c.elevation(), -OrbitController::MAX_ELEVATION);
    c.reset();
    EXPECT_EQ(c.azimuth(), 0.0);
    EXPECT_EQ(c.elevation(), 10.0);

    // Pan: the point at the target follows the cursor, pixel for pixel.
    const render::Camera before = c.camera(400, 300);
    const Vec3d target = c.target();
    c.pan(40.0, -25.0, 300);
    const render::PixelPoint moved = c.camera(400, 300).project(target);
    const render::PixelPoint was = before.project(target);
    EXPECT_NEAR(moved.x - was.x, 40.0, 1e-9);
    EXPECT_NEAR(moved.y - was.y, -25.0, 1e-9);

    const unsigned long long generation = c.generation();
    c.zoom(2.0);
    EXPECT_NEAR(c.distance(), 10.0 * 0.81, 1e-12);
    EXPECT_GT(c.generation(), generation);
    c.zoom(1e6);  // never through the target
    EXPECT_GT(c.distance(), 0.0);
    EXPECT_NO_THROW(c.camera(400, 300));
}

TEST(OrbitController, RejectsBadInput) {
    EXPECT_THROW(OrbitController(AABBd{}, 0.0, 0.0, 1.0, 10, 10), InvalidInput);
    EXPECT_THROW(OrbitController(BOX, std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0, 10, 10),
                 InvalidInput);
    EXPECT_THROW(OrbitController(BOX, 0.0, 0.0, std::numeric_limits<double>::infinity(), 10, 10),
                 InvalidInput);
}

}  // namespace
}  // namespace pliant::viewer
