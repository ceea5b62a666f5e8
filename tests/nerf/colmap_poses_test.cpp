// COLMAP → radiance-field poses: a hand-checked camera, the round trip synthetic cameras →
// COLMAP text model → read → transforms equal to the originals within 1e-9, and the
// normalization's centre, scale and orientation on cameras circling a known point.
#include "pliant/nerf/colmap_poses.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "../support/test_files.hpp"
#include "pliant/core/error.hpp"

namespace pliant::nerf {
namespace {

// A camera at `eye` looking at `target` with `up` roughly up (OpenGL axes).
Pose look_at(Vec3d eye, Vec3d target, Vec3d up) {
    const Vec3d z = (eye - target) / norm(eye - target);
    Vec3d x = cross(up, z);
    x = x / norm(x);
    const Vec3d y = cross(z, x);
    return Pose{{x.x, y.x, z.x, eye.x, x.y, y.y, z.y, eye.y, x.z, y.z, z.z, eye.z}};
}

TEST(ColmapPoses, IdentityQuaternionByHand) {
    // x_cam = x_world + (0, 0, 4): the camera sits at (0, 0, −4) looking down +z (COLMAP's
    // forward), y down; in OpenGL axes its y is (0, −1, 0) and it looks down its −z = +z world.
    const Pose p = pose_from_colmap({1, 0, 0, 0}, {0, 0, 4});
    EXPECT_EQ(p.eye(), (Vec3d{0, 0, -4}));
    EXPECT_EQ(p.axis(0), (Vec3d{1, 0, 0}));
    EXPECT_EQ(p.axis(1), (Vec3d{0, -1, 0}));
    EXPECT_EQ(p.axis(2), (Vec3d{0, 0, -1}));
    EXPECT_THROW(pose_from_colmap({0, 0, 0, 0}, {0, 0, 0}), InvalidInput);
}

TEST(ColmapPoses, QuarterTurnByHand) {
    // q = (cos 45°, 0, sin 45°, 0): R rotates +90° about y: R x = (z, y, −x). The camera's
    // forward (row 2 of R) is (1, 0, 0)... in world: rows of R are the camera axes.
    const double h = std::sqrt(0.5);
    const Pose p = pose_from_colmap({h, 0, h, 0}, {0, 0, 0});
    const Vec3d forward = -p.axis(2);  // OpenGL looks down −z
    EXPECT_NEAR(forward.x, -1.0, 1e-15);
    EXPECT_NEAR(forward.y, 0.0, 1e-15);
    EXPECT_NEAR(forward.z, 0.0, 1e-15);
}

TEST(ColmapPoses, SyntheticCamerasRoundTripThroughATextModel) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Pose> poses;
    io::ColmapModel model;
    Intrinsics in;
    in.width = 480;
    in.height = 360;
    in.fx = 410.25;
    in.fy = 409.5;
    in.cx = 241.3;
    in.cy = 178.9;
    in.lens = Lens{.model = LensModel::opencv, .k1 = -0.08, .k2 = 0.01, .p1 = 1e-3, .p2 = -5e-4};
    model.cameras.push_back(colmap_camera_from_intrinsics(in, 1));
    for (int i = 0; i < 12; ++i) {
        const Vec3d eye{3.0 * u(rng), 3.0 * u(rng), 3.0 * u(rng) + 4.0};
        const Pose p = look_at(eye, Vec3d{u(rng), u(rng), u(rng)} * 0.2, Vec3d{u(rng), 1.0, 0.3});
        poses.push_back(p);
        io::ColmapImage im;
        im.id = static_cast<std::uint32_t>(100 - i);
        im.camera_id = 1;
        im.name = "img_" + std::to_string(10 + i) + ".jpg";
        colmap_from_pose(p, im.qvec, im.tvec);
        model.images.push_back(im);
    }
    io::test::TempDir dir;
    io::write_colmap_model(dir.path(), model, io::ColmapFormat::text);
    const io::ColmapModel read = io::read_colmap_model(dir.path());
    const ColmapTransforms t =
        transforms_from_colmap(read, {.centre = ColmapCentre::none, .scale = ColmapScale::none});
    ASSERT_EQ(t.frames.size(), poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) {
        EXPECT_EQ(t.frames[i].file_path, "img_" + std::to_string(10 + i) + ".jpg");
        for (std::size_t k = 0; k < 12; ++k) {
            EXPECT_NEAR(t.frames[i].camera_to_world.m[k], poses[i].m[k], 1e-9) << i << " " << k;
        }
        const Intrinsics& r = t.frames[i].intrinsics;
        EXPECT_EQ(r.width, 480);
        EXPECT_EQ(r.fx, in.fx);
        EXPECT_EQ(r.fy, in.fy);
        EXPECT_EQ(r.cx, in.cx);
        EXPECT_EQ(r.cy, in.cy);
        EXPECT_EQ(r.lens.model, LensModel::opencv);
        EXPECT_EQ(r.lens.k1, in.lens.k1);
        EXPECT_EQ(r.lens.p2, in.lens.p2);
    }
    EXPECT_EQ(t.scale, 1.0);
}

TEST(ColmapPoses, NormalizationCentresOnTheFocusAndScales) {
    // 16 cameras on a circle of radius 5 at height 1 around (1, 2, 3), all looking at it.
    const Vec3d target{1, 2, 3};
    io::ColmapModel model;
    Intrinsics in;
    in.width = 100;
    in.height = 100;
    in.fx = in.fy = 80;
    in.cx = in.cy = 50;
    model.cameras.push_back(colmap_camera_from_intrinsics(in, 3));
    for (int i = 0; i < 16; ++i) {
        const double a = 2.0 * std::numbers::pi * i / 16.0;
        const Vec3d eye = target + Vec3d{5.0 * std::cos(a), 1.0, 5.0 * std::sin(a)};
        io::ColmapImage im;
        im.id = static_cast<std::uint32_t>(i + 1);
        im.camera_id = 3;
        im.name = fmt::format("{:02}.png", i);
        colmap_from_pose(look_at(eye, target, Vec3d{0, 1, 0}), im.qvec, im.tvec);
        model.images.push_back(im);
    }
    // Cameras: centre → target, max |coordinate| of the centred eyes = 5.
    ColmapTransforms t = transforms_from_colmap(model, {.scale = ColmapScale::points});
    EXPECT_EQ(t.scale_used, ColmapScale::cameras);  // no points: the fallback
    EXPECT_NEAR(t.centre.x, 1.0, 1e-9);
    EXPECT_NEAR(t.centre.y, 2.0, 1e-9);
    EXPECT_NEAR(t.centre.z, 3.0, 1e-9);
    EXPECT_NEAR(t.scale, 0.2, 1e-12);
    EXPECT_NEAR(t.frames[0].camera_to_world.eye().x, 1.0, 1e-9);
    EXPECT_NEAR(t.frames[0].camera_to_world.eye().y, 0.2, 1e-9);
    // Points: 100 points in a cube of half-side 0.5 around the target plus 5 % far outliers;
    // the 0.95 quantile of their ∞-norm distance is just below 0.5.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (int i = 0; i < 100; ++i) {
        io::ColmapPoint3D p;
        p.id = static_cast<std::uint64_t>(i);
        const double far = i < 5 ? 40.0 : 1.0;
        p.xyz = {target.x + far * u(rng), target.y + far * u(rng), target.z + far * u(rng)};
        if (i >= 5 && i < 10) {
            p.xyz = {target.x + 0.5, target.y, target.z};  // a few at exactly 0.5
        }
        model.points.push_back(p);
    }
    t = transforms_from_colmap(model);
    EXPECT_EQ(t.scale_used, ColmapScale::points);
    EXPECT_GT(t.scale, 1.0 / 0.5 - 1e-9);
    EXPECT_LT(t.scale, 1.0 / 0.4);
    int inside = 0;
    for (const Vec3d& p : t.points) {
        inside += within_cube(p, 1.0 + 1e-12) ? 1 : 0;
    }
    EXPECT_GE(inside, 95);
    // world_from_colmap maps the COLMAP points to t.points.
    const auto& m = t.world_from_colmap;
    const auto& x = model.points[20].xyz;
    EXPECT_NEAR(m[0] * x[0] + m[1] * x[1] + m[2] * x[2] + m[3], t.points[20].x, 1e-12);
    EXPECT_NEAR(m[8] * x[0] + m[9] * x[1] + m[10] * x[2] + m[11], t.points[20].z, 1e-12);
}

TEST(ColmapPoses, OrientUpTakesTheMeanUpToPlusZ) {
    io::ColmapModel model;
    Intrinsics in;
    in.width = in.height = 64;
    in.fx = in.fy = 50;
    in.cx = in.cy = 32;
    model.cameras.push_back(colmap_camera_from_intrinsics(in, 1));
    const Vec3d up = Vec3d{0.3, -0.8, 0.52} / norm(Vec3d{0.3, -0.8, 0.52});
    for (int i = 0; i < 8; ++i) {
        const double a = 2.0 * std::numbers::pi * i / 8.0;
        // Cameras circling in the plane perpendicular to `up`.
        Vec3d e1 = cross(up, Vec3d{1, 0, 0});
        e1 = e1 / norm(e1);
        const Vec3d e2 = cross(up, e1);
        const Vec3d eye = 4.0 * (std::cos(a) * e1 + std::sin(a) * e2);
        io::ColmapImage im;
        im.id = static_cast<std::uint32_t>(i + 1);
        im.camera_id = 1;
        im.name = std::to_string(i);
        colmap_from_pose(look_at(eye, Vec3d{}, up), im.qvec, im.tvec);
        model.images.push_back(im);
    }
    const ColmapTransforms t = transforms_from_colmap(
        model,
        {.orient_up = true, .centre = ColmapCentre::camera_mean, .scale = ColmapScale::none});
    for (const ColmapFrame& f : t.frames) {
        const Vec3d y = f.camera_to_world.axis(1);
        EXPECT_NEAR(y.z, 1.0, 1e-9);
        EXPECT_NEAR(f.camera_to_world.eye().z, 0.0, 1e-9);
        EXPECT_NEAR(f.camera_to_world.determinant(), 1.0, 1e-12);
    }
}

TEST(ColmapPoses, IntrinsicsOfEveryModel) {
    io::ColmapCamera c;
    c.width = 10;
    c.height = 8;
    c.model_id = 3;  // RADIAL f cx cy k1 k2
    c.params = {7, 5.5, 4.5, 0.1, 0.2};
    Intrinsics in = intrinsics_from_colmap(c);
    EXPECT_EQ(in.fx, 7.0);
    EXPECT_EQ(in.fy, 7.0);
    EXPECT_EQ(in.cx, 5.5);
    EXPECT_EQ(in.lens.model, LensModel::radial);
    EXPECT_EQ(in.lens.k2, 0.2);
    c.model_id = 5;  // OPENCV_FISHEYE fx fy cx cy k1 k2 k3 k4
    c.params = {7, 8, 5, 4, 0.1, 0.2, 0.3, 0.4};
    in = intrinsics_from_colmap(c);
    EXPECT_EQ(in.fy, 8.0);
    EXPECT_EQ(in.lens.k4, 0.4);
    EXPECT_EQ(colmap_camera_from_intrinsics(in, 1).params, c.params);
    c.model_id = 7;  // FOV
    c.params = {7, 8, 5, 4, 0.1};
    try {
        intrinsics_from_colmap(c);
        FAIL();
    } catch (const Unsupported& e) {
        EXPECT_NE(std::string(e.what()).find("FOV"), std::string::npos) << e.what();
    }
    EXPECT_THROW(transforms_from_colmap(io::ColmapModel{}), InvalidInput);
}

}  // namespace
}  // namespace pliant::nerf
