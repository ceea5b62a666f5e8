#include "pliant/render/camera.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "pliant/core/error.hpp"

namespace pliant::render {
namespace {

TEST(Camera, PerspectiveKnownProjections) {
    // fov 90°, 200 × 100: f = 50 / tan(45°) = 50 pixels per unit of cx/depth.
    const Camera cam = Camera::perspective({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 90.0, 200, 100);
    EXPECT_NEAR(cam.focal_pixels(), 50.0, 1e-12);
    EXPECT_EQ(cam.right(), (Vec3d{1, 0, 0}));
    EXPECT_EQ(cam.up(), (Vec3d{0, 1, 0}));
    EXPECT_EQ(cam.forward(), (Vec3d{0, 0, -1}));
    const PixelPoint c = cam.project({0, 0, 0});
    EXPECT_DOUBLE_EQ(c.x, 100.0);
    EXPECT_DOUBLE_EQ(c.y, 50.0);
    EXPECT_DOUBLE_EQ(c.depth, 5.0);
    const PixelPoint px = cam.project({1, 0, 0});  // right of centre
    EXPECT_NEAR(px.x, 110.0, 1e-12);
    EXPECT_NEAR(px.y, 50.0, 1e-12);
    const PixelPoint py = cam.project({0, 1, 0});  // up is towards row 0
    EXPECT_NEAR(py.x, 100.0, 1e-12);
    EXPECT_NEAR(py.y, 40.0, 1e-12);
    // The top edge of the image is at the half field of view: y = 0 at cy/depth = tan 45° = 1.
    EXPECT_NEAR(cam.project({0, 2.5, 2.5}).y, 0.0, 1e-12);
    EXPECT_NEAR(cam.near(), 5e-3, 1e-15);
}

TEST(Camera, OrthographicKnownProjections) {
    const Camera cam = Camera::orthographic({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 4.0, 200, 100);
    EXPECT_DOUBLE_EQ(cam.focal_pixels(), 25.0);
    const PixelPoint p = cam.project({1, 1, -3});
    EXPECT_DOUBLE_EQ(p.x, 125.0);
    EXPECT_DOUBLE_EQ(p.y, 25.0);
    EXPECT_DOUBLE_EQ(p.depth, 8.0);
    const Ray r = cam.pixel_ray(0, 0);  // centre (0.5, 0.5)
    EXPECT_EQ(r.direction, (Vec3d{0, 0, -1}));
    EXPECT_NEAR(r.origin.x, (0.5 - 100.0) / 25.0, 1e-12);
    EXPECT_NEAR(r.origin.y, (50.0 - 0.5) / 25.0, 1e-12);
}

TEST(Camera, BasisIsOrthonormalAndRightHanded) {
    const Camera cam = Camera::perspective({3, -4, 2}, {0.5, 1, -1}, {0, 0, 1}, 40.0, 64, 48);
    EXPECT_NEAR(norm(cam.right()), 1.0, 1e-15);
    EXPECT_NEAR(norm(cam.up()), 1.0, 1e-15);
    EXPECT_NEAR(dot(cam.right(), cam.up()), 0.0, 1e-15);
    EXPECT_NEAR(dot(cam.right(), cam.forward()), 0.0, 1e-15);
    const Vec3d back = cross(cam.right(), cam.up());  // right × up = −forward
    EXPECT_NEAR(back.x, -cam.forward().x, 1e-15);
    EXPECT_NEAR(back.y, -cam.forward().y, 1e-15);
    EXPECT_NEAR(back.z, -cam.forward().z, 1e-15);
    EXPECT_GT(cam.up().z, 0.0);  // the +z hint stays up in the image
}

TEST(Camera, PixelRaysProjectBackToPixelCentres) {
    for (const Projection projection : {Projection::perspective, Projection::orthographic}) {
        const Camera cam =
            projection == Projection::perspective
                ? Camera::perspective({1, -6, 3}, {0, 0, 0.5}, {0, 0, 1}, 35.0, 37, 23)
                : Camera::orthographic({1, -6, 3}, {0, 0, 0.5}, {0, 0, 1}, 3.0, 37, 23);
        for (int j = 0; j < 23; j += 5) {
            for (int i = 0; i < 37; i += 6) {
                const Ray r = cam.pixel_ray(i, j);
                ASSERT_NEAR(norm(r.direction), 1.0, 1e-14);
                for (const double t : {0.5, 3.0, 40.0}) {
                    const PixelPoint p = cam.project(r.origin + t * r.direction);
                    ASSERT_NEAR(p.x, i + 0.5, 1e-9) << i << "," << j << " t " << t;
                    ASSERT_NEAR(p.y, j + 0.5, 1e-9) << i << "," << j << " t " << t;
                    ASSERT_GT(p.depth, 0.0);
                }
            }
        }
    }
}

TEST(Camera, FramingKeepsEveryBoxCornerInsideTheImage) {
    const AABBd boxes[] = {{{-1, -1, 0}, {1, 1, 1.2}},
                           {{-0.1, 2, 3}, {5, 2.5, 3.01}},
                           {{1e-3, 1e-3, 1e-3}, {2e-3, 5e-3, 1.5e-3}},
                           {{2, 2, 2}, {2, 2, 2}}};  // a point
    const int sizes[][2] = {{640, 480}, {100, 300}, {33, 33}};
    for (const AABBd& box : boxes) {
        for (const auto& size : sizes) {
            for (const double az : {0.0, 37.0, 135.0, -90.0}) {
                for (const double el : {-90.0, -30.0, 0.0, 25.0, 89.0, 90.0}) {
                    for (const Projection proj :
                         {Projection::perspective, Projection::orthographic}) {
                        FramingOptions options;
                        options.projection = proj;
                        const Camera cam = frame_box(box, az, el, size[0], size[1], options);
                        for (int k = 0; k < 8; ++k) {
                            const Vec3d corner{(k & 1) ? box.hi.x : box.lo.x,
                                               (k & 2) ? box.hi.y : box.lo.y,
                                               (k & 4) ? box.hi.z : box.lo.z};
                            const PixelPoint p = cam.project(corner);
                            ASSERT_GT(p.depth, cam.near());
                            ASSERT_GE(p.x, 0.0) << az << " " << el;
                            ASSERT_LE(p.x, size[0]) << az << " " << el;
                            ASSERT_GE(p.y, 0.0) << az << " " << el;
                            ASSERT_LE(p.y, size[1]) << az << " " << el;
                        }
                        // The view direction follows azimuth and elevation.
                        const Vec3d to_eye = cam.eye() - box.center();
                        const double el_rad = el * std::numbers::pi / 180.0;
                        EXPECT_NEAR(to_eye.z / norm(to_eye), std::sin(el_rad), 1e-9);
                    }
                }
            }
        }
    }
}

TEST(Camera, FramingFromTheSideHasZUp) {
    const Camera cam = frame_box({{-1, -1, -1}, {1, 1, 1}}, 0.0, 0.0, 64, 64);
    EXPECT_NEAR(cam.eye().y, 0.0, 1e-12);
    EXPECT_GT(cam.eye().x, 1.0);                                     // azimuth 0 looks from +x
    EXPECT_LT(cam.project({0, 0, 1}).y, cam.project({0, 0, -1}).y);  // +z is up in the image
    // Azimuth 90 looks from +y towards −y; with +z up, +x is then on the left of the image.
    const Camera side = frame_box({{-1, -1, -1}, {1, 1, 1}}, 90.0, 0.0, 64, 64);
    EXPECT_GT(side.eye().y, 1.0);
    EXPECT_LT(side.project({1, 0, 0}).x, side.project({-1, 0, 0}).x);
}

TEST(Camera, RejectsBadArguments) {
    const Vec3d e{0, 0, 5}, t{0, 0, 0}, up{0, 1, 0};
    EXPECT_THROW(Camera::perspective(e, e, up, 45.0, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::perspective(e, t, {0, 0, 1}, 45.0, 10, 10), InvalidInput);  // parallel
    EXPECT_THROW(Camera::perspective(e, t, {0, 0, 0}, 45.0, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::perspective(e, t, up, 0.0, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::perspective(e, t, up, 180.0, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::perspective(e, t, up, NAN, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::perspective({NAN, 0, 0}, t, up, 45.0, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::orthographic(e, t, up, 0.0, 10, 10), InvalidInput);
    EXPECT_THROW(Camera::orthographic(e, t, up, 1.0, 0, 10), InvalidInput);
    EXPECT_THROW(frame_box(AABBd{}, 0.0, 0.0, 10, 10), InvalidInput);  // empty box
    EXPECT_THROW(frame_box({{0, 0, 0}, {1, 1, 1}}, NAN, 0.0, 10, 10), InvalidInput);
    Camera cam = Camera::perspective(e, t, up, 45.0, 10, 10);
    EXPECT_THROW(cam.set_near(0.0), InvalidInput);
    try {
        Camera::perspective(e, t, up, 45.0, 10, -3);
        FAIL();
    } catch (const InvalidInput& ex) {
        EXPECT_NE(std::string(ex.what()).find("10 x -3"), std::string::npos) << ex.what();
    }
}

}  // namespace
}  // namespace pliant::render
