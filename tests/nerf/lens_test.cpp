// Lens models: hand-computed values of the OpenCV / COLMAP formulas, distort ∘ undistort round
// trips over whole images, the fold-back refusal, names and coefficient validation.
#include "pliant/nerf/lens.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "pliant/core/error.hpp"

namespace pliant::nerf {
namespace {

TEST(Lens, OpencvMatchesHandComputedValue) {
    // u = 0.3, v = −0.2, k1 = 0.1, k2 = 0.01, p1 = 0.001, p2 = 0.002: r² = 0.13,
    // radial = 1.013169, u_d = 0.3 · 1.013169 − 0.00012 + 0.00062, v_d = −0.2 · 1.013169 −
    // 0.00024 + 0.00021.
    Lens lens{.model = LensModel::opencv, .k1 = 0.1, .k2 = 0.01, .p1 = 0.001, .p2 = 0.002};
    const Point2 d = distort(lens, {0.3, -0.2});
    EXPECT_NEAR(d.x, 0.3044507, 1e-15);
    EXPECT_NEAR(d.y, -0.2026638, 1e-15);
}

TEST(Lens, FisheyeMatchesHandComputedValue) {
    // θ = atan(|(0.5, 0.25)|), θ_d = θ (1 + k1 θ² + k2 θ⁴ + k3 θ⁶ + k4 θ⁸), scaled by θ_d / r.
    Lens lens{
        .model = LensModel::opencv_fisheye, .k1 = 0.05, .k2 = -0.01, .k3 = 0.002, .k4 = -0.0003};
    const Point2 d = distort(lens, {0.5, 0.25});
    EXPECT_NEAR(d.x, 0.46155584206995737, 1e-15);
    EXPECT_NEAR(d.y, 0.23077792103497868, 1e-15);
    EXPECT_EQ(distort(lens, {0.0, 0.0}).x, 0.0);
}

TEST(Lens, SimpleModelsAreOpencvSpecialCases) {
    const Lens simple{.model = LensModel::simple_radial, .k1 = -0.07};
    const Lens radial{.model = LensModel::radial, .k1 = -0.07, .k2 = 0.0};
    const Lens opencv{.model = LensModel::opencv, .k1 = -0.07};
    for (const Point2 p : {Point2{0.1, 0.2}, Point2{-0.4, 0.3}}) {
        // u (1 + k1 r²) by hand.
        const double r2 = p.x * p.x + p.y * p.y;
        EXPECT_DOUBLE_EQ(distort(simple, p).x, p.x * (1.0 - 0.07 * r2));
        EXPECT_DOUBLE_EQ(distort(radial, p).y, distort(opencv, p).y);
    }
}

// distort(undistort(p)) == p within 1e-6 pixels at every 3rd pixel of a 640 × 480 image with
// fx = fy = 500, and undistort(distort(q)) == q.
void expect_round_trip(const Lens& lens) {
    const double f = 500.0, cx = 320.0, cy = 240.0;
    double worst = 0.0;
    for (int y = 0; y <= 480; y += 3) {
        for (int x = 0; x <= 640; x += 3) {
            const Point2 d{(x - cx) / f, (y - cy) / f};
            const std::optional<Point2> u = undistort(lens, d);
            ASSERT_TRUE(u.has_value()) << lens_model_name(lens.model) << " at " << x << ", " << y;
            const Point2 back = distort(lens, *u);
            worst = std::max({worst, std::fabs(back.x - d.x) * f, std::fabs(back.y - d.y) * f});
            const std::optional<Point2> again = undistort(lens, distort(lens, d));
            ASSERT_TRUE(again.has_value());
            worst = std::max({worst, std::fabs(again->x - d.x) * f, std::fabs(again->y - d.y) * f});
        }
    }
    EXPECT_LT(worst, 1e-6) << lens_model_name(lens.model);
}

TEST(Lens, UndistortInvertsDistortOverTheImage) {
    expect_round_trip({.model = LensModel::simple_radial, .k1 = -0.12});
    expect_round_trip({.model = LensModel::radial, .k1 = 0.08, .k2 = -0.02});
    expect_round_trip(
        {.model = LensModel::opencv, .k1 = -0.15, .k2 = 0.04, .p1 = 0.002, .p2 = -0.0015});
    expect_round_trip({.model = LensModel::opencv,
                       .k1 = 0.1,
                       .k2 = 0.01,
                       .k3 = -0.002,
                       .k4 = 0.0005,
                       .p1 = -0.001,
                       .p2 = 0.001});
    expect_round_trip(
        {.model = LensModel::opencv_fisheye, .k1 = 0.05, .k2 = -0.01, .k3 = 0.002, .k4 = -0.0003});
    expect_round_trip({.model = LensModel::pinhole});
}

TEST(Lens, PinholeUndistortIsTheIdentity) {
    const Lens lens;
    const std::optional<Point2> u = undistort(lens, {0.123, -0.456});
    ASSERT_TRUE(u);
    EXPECT_EQ(u->x, 0.123);
    EXPECT_EQ(u->y, -0.456);
}

TEST(Lens, FisheyeDirectionBeyondNinetyDegrees) {
    // θ_d = 2 with no coefficients: θ = 2 rad > π / 2, a ray behind the image plane.
    const Lens lens{.model = LensModel::opencv_fisheye, .k1 = 1e-9};
    const std::optional<Vec3d> d = undistorted_direction(lens, {2.0, 0.0});
    ASSERT_TRUE(d);
    EXPECT_NEAR(d->x, std::sin(2.0), 1e-7);
    EXPECT_NEAR(d->z, std::cos(2.0), 1e-7);
    EXPECT_FALSE(undistort(lens, {2.0, 0.0}).has_value());  // no pinhole coordinates
}

TEST(Lens, FoldBackIsReportedNotGuessed) {
    // u (1 − 0.5 u²) peaks at u_d = 0.544 (u = 0.816): a distorted 0.6 has no preimage.
    const Lens lens{.model = LensModel::simple_radial, .k1 = -0.5};
    EXPECT_FALSE(undistorted_direction(lens, {0.6, 0.0}).has_value());
    EXPECT_TRUE(undistorted_direction(lens, {0.5, 0.0}).has_value());
    EXPECT_FALSE(undistorted_direction(lens, {std::nan(""), 0.0}).has_value());
}

TEST(Lens, NamesRoundTrip) {
    for (const LensModel m :
         {LensModel::simple_pinhole, LensModel::pinhole, LensModel::simple_radial,
          LensModel::radial, LensModel::opencv, LensModel::opencv_fisheye}) {
        EXPECT_EQ(lens_model_from_name(lens_model_name(m)), m);
    }
    EXPECT_FALSE(lens_model_from_name("FOV").has_value());
    EXPECT_NE(lens_model_names().find("OPENCV_FISHEYE"), std::string::npos);
}

TEST(Lens, ValidateNamesTheCoefficientTheModelLacks) {
    try {
        validate(Lens{.model = LensModel::pinhole, .k1 = 0.1}, "transforms.json");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("k1"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("PINHOLE"), std::string::npos) << e.what();
    }
    EXPECT_THROW(validate(Lens{.model = LensModel::opencv_fisheye, .p1 = 0.1}, "x"), InvalidInput);
    EXPECT_THROW(validate(Lens{.model = LensModel::opencv, .k1 = INFINITY}, "x"), InvalidInput);
    EXPECT_NO_THROW(validate(Lens{.model = LensModel::opencv, .k4 = 0.1, .p2 = 0.1}, "x"));
}

}  // namespace
}  // namespace pliant::nerf
