// Dataset rays through lens models: the distortion-free ray is the pinhole formula bit for bit;
// a distorted ray projects back (forward projection: camera frame → distort → pixel) onto its
// pixel; intrinsics validation refuses folding lenses and foreign coefficients.
#include "pliant/nerf/dataset.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pliant/core/error.hpp"

namespace pliant::nerf {
namespace {

Pose tilted_pose() {
    // Orthonormal axes from a rotation about (1, 2, 3) by 0.7 rad (Rodrigues), eye (0.5, −1, 4).
    const Vec3d k = Vec3d{1, 2, 3} / norm(Vec3d{1, 2, 3});
    const double c = std::cos(0.7), s = std::sin(0.7);
    Pose p;
    for (int col = 0; col < 3; ++col) {
        const Vec3d e{col == 0 ? 1.0 : 0.0, col == 1 ? 1.0 : 0.0, col == 2 ? 1.0 : 0.0};
        const Vec3d r = c * e + s * cross(k, e) + (1 - c) * dot(k, e) * k;
        p.m[col] = r.x;
        p.m[4 + col] = r.y;
        p.m[8 + col] = r.z;
    }
    p.m[3] = 0.5;
    p.m[7] = -1.0;
    p.m[11] = 4.0;
    return p;
}

Intrinsics intrinsics(Lens lens) {
    Intrinsics in;
    in.width = 64;
    in.height = 48;
    in.fx = 55.5;
    in.fy = 54.25;
    in.cx = 31.7;
    in.cy = 24.9;
    in.lens = lens;
    return in;
}

TEST(DatasetRays, WithoutDistortionTheRayIsThePinholeFormulaBitwise) {
    const Pose pose = tilted_pose();
    // PINHOLE, and OPENCV with every coefficient zero: the same code path.
    for (const Lens lens : {Lens{}, Lens{.model = LensModel::opencv}}) {
        const Intrinsics in = intrinsics(lens);
        for (int y = 0; y < in.height; y += 5) {
            for (int x = 0; x < in.width; x += 3) {
                const double px = x + 0.5, py = y + 0.5;
                const double u = (px - in.cx) / in.fx;
                const double v = -(py - in.cy) / in.fy;
                const Vec3d d = u * pose.axis(0) + v * pose.axis(1) - pose.axis(2);
                const Vec3d expected = d / norm(d);
                const render::Ray r = view_ray(in, pose, px, py);
                EXPECT_EQ(r.direction, expected);
                EXPECT_EQ(r.origin, pose.eye());
            }
        }
    }
}

// Forward projection of a world direction: camera frame (OpenCV axes) → normalized → distort →
// pixel.
void expect_ray_projects_back(const Intrinsics& in, const Pose& pose) {
    double worst = 0.0;
    for (int y = 0; y < in.height; y += 4) {
        for (int x = 0; x < in.width; x += 4) {
            const double px = x + 0.5, py = y + 0.5;
            const Vec3d d = view_ray(in, pose, px, py).direction;
            // OpenCV camera frame: x = axis 0, y = −axis 1, z = −axis 2.
            const double cx = dot(d, pose.axis(0)), cy = -dot(d, pose.axis(1)),
                         cz = -dot(d, pose.axis(2));
            ASSERT_GT(cz, 0.0);
            const Point2 p = distort(in.lens, {cx / cz, cy / cz});
            worst = std::max(
                {worst, std::fabs(in.fx * p.x + in.cx - px), std::fabs(in.fy * p.y + in.cy - py)});
        }
    }
    EXPECT_LT(worst, 1e-6) << lens_model_name(in.lens.model);
}

TEST(DatasetRays, DistortedRaysProjectBackOntoTheirPixels) {
    const Pose pose = tilted_pose();
    expect_ray_projects_back(intrinsics({.model = LensModel::simple_radial, .k1 = -0.2}), pose);
    expect_ray_projects_back(
        intrinsics(
            {.model = LensModel::opencv, .k1 = 0.12, .k2 = -0.03, .p1 = 0.004, .p2 = -0.002}),
        pose);
    expect_ray_projects_back(
        intrinsics({.model = LensModel::opencv_fisheye, .k1 = 0.03, .k2 = -0.01, .k4 = 0.001}),
        pose);
}

TEST(DatasetRays, DistortionChangesTheRays) {
    // The symptom: with and without k1 the rays must differ away from the centre.
    const Pose pose = tilted_pose();
    const Vec3d a = view_ray(intrinsics({}), pose, 2.5, 3.5).direction;
    const Vec3d b =
        view_ray(intrinsics({.model = LensModel::simple_radial, .k1 = -0.2}), pose, 2.5, 3.5)
            .direction;
    EXPECT_GT(norm(a - b), 1e-3);
}

TEST(DatasetRays, ValidateRefusesFoldingLensesAndForeignCoefficients) {
    EXPECT_NO_THROW(validate(intrinsics({.model = LensModel::opencv, .k1 = -0.1}), "t"));
    // u (1 − 0.9 u²) peaks at u_d ≈ 0.41 (u = 0.61); the corner of 64 × 48 at f = 55 reaches
    // |u_d| ≈ 0.58 along x: no preimage there.
    try {
        validate(intrinsics({.model = LensModel::simple_radial, .k1 = -0.9}), "t.json");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("folds back"), std::string::npos) << e.what();
    }
    EXPECT_THROW(validate(intrinsics({.model = LensModel::pinhole, .p1 = 0.1}), "t"), InvalidInput);
    Intrinsics bad = intrinsics({});
    bad.fx = -1.0;
    EXPECT_THROW(validate(bad, "t"), InvalidInput);
}

TEST(DatasetRays, PerViewIntrinsicsAndMasksAreValidated) {
    Dataset ds;
    ds.intrinsics = intrinsics({});
    View v;
    v.rgb.assign(3 * 64 * 48, 0.0f);
    ds.views.push_back(v);
    EXPECT_NO_THROW(validate(ds));
    ds.views[0].intrinsics = intrinsics({.model = LensModel::radial, .k1 = 0.01, .k2 = 0.001});
    EXPECT_NO_THROW(validate(ds));
    EXPECT_EQ(intrinsics_of(ds, ds.views[0]).lens.model, LensModel::radial);
    ds.views[0].intrinsics->width = 32;
    EXPECT_THROW(validate(ds), InvalidInput);
    ds.views[0].intrinsics.reset();
    ds.views[0].mask.assign(10, 1);
    EXPECT_THROW(validate(ds), InvalidInput);
    ds.views[0].mask.assign(64 * 48, 1);
    EXPECT_NO_THROW(validate(ds));
}

TEST(DatasetRays, TheRayCasterCameraRefusesALens) {
    EXPECT_THROW(
        camera_from_view(intrinsics({.model = LensModel::opencv, .k1 = 0.1}), tilted_pose()),
        Unsupported);
}

}  // namespace
}  // namespace pliant::nerf
