// Per-view exposure and camera refinement while training (trainer.hpp, camera_refinement.hpp)
// on tiny synthetic scenes whose truth is known: views rendered from a ground-truth field, then
// given per-view gains or perturbed cameras.
#include "pliant/nerf/camera_refinement.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <vector>

#include "ball_scene.hpp"
#include "pliant/core/error.hpp"
#include "pliant/core/parallel.hpp"
#include "pliant/nerf/detail/field_kernel.hpp"
#include "pliant/nerf/metrics.hpp"
#include "pliant/nerf/pose_alignment.hpp"
#include "pliant/nerf/render.hpp"
#include "pliant/nerf/trainer.hpp"

namespace pliant::nerf {
namespace {

using test::make_dataset;
using test::mean_psnr;
using test::tiny_options;

RadianceGrid ball_field(int resolution) {
    return test::ball_field(resolution, true);
}

const auto none = [](const TrainProgress&) {
    return true;
};

TEST(CameraRefinement, AxisAngleIsRodrigues) {
    const Vec3d w{0.0, 0.0, std::numbers::pi / 2};
    const std::array<double, 9> r = rotation_from_axis_angle(w);
    // A quarter turn about z: x → y.
    EXPECT_NEAR(r[0], 0.0, 1e-12);
    EXPECT_NEAR(r[3], 1.0, 1e-12);
    EXPECT_NEAR(r[1], -1.0, 1e-12);
    const std::array<double, 9> small = rotation_from_axis_angle({1e-6, -2e-6, 3e-6});
    EXPECT_NEAR(small[1], -3e-6, 1e-11);  // I + [ω]x + O(|ω|²)
    EXPECT_NEAR(small[2], -2e-6, 1e-11);
    Pose p;
    p.m[3] = 1.0;
    const Pose q = refined_pose(p, w, {0.0, 0.5, 0.0});
    EXPECT_NEAR(q.axis(0).y, 1.0, 1e-12);
    EXPECT_NEAR(q.eye().x, 1.0, 1e-12);
    EXPECT_NEAR(q.eye().y, 0.5, 1e-12);
}

// Held-out poses follow the similarity that moved the training eyes.
TEST(CameraRefinement, TransferMovesHeldOutViewsWithTheRig) {
    std::vector<Pose> original, moved, held_out(1);
    const Vec3d w{0.0, 0.0, 0.3};
    for (int i = 0; i < 5; ++i) {
        Pose p;
        p.m[3] = std::cos(i * 1.2);
        p.m[7] = std::sin(i * 1.2);
        p.m[11] = 0.1 * i;
        original.push_back(p);
        // The whole rig turned by w about the origin, scaled by 2 and shifted.
        const std::array<double, 9> r = rotation_from_axis_angle(w);
        Pose m = refined_pose(p, w, {});
        const Vec3d e = p.eye();
        m.m[3] = 2.0 * (r[0] * e.x + r[1] * e.y + r[2] * e.z) + 0.5;
        m.m[7] = 2.0 * (r[3] * e.x + r[4] * e.y + r[5] * e.z);
        m.m[11] = 2.0 * (r[6] * e.x + r[7] * e.y + r[8] * e.z);
        moved.push_back(m);
    }
    held_out[0].m[3] = 0.2;
    const std::vector<Pose> t = transfer_refinement(original, moved, held_out);
    ASSERT_EQ(t.size(), 1u);
    EXPECT_NEAR(t[0].eye().x, 2.0 * 0.2 * std::cos(0.3) + 0.5, 1e-9);
    EXPECT_NEAR(t[0].eye().y, 2.0 * 0.2 * std::sin(0.3), 1e-9);
    EXPECT_NEAR(rotation_angle_deg(t[0], refined_pose(held_out[0], w, {})), 0.0, 1e-6);
    EXPECT_THROW(transfer_refinement(original, held_out, held_out), InvalidInput);
}

// position_gradient is the derivative of the interpolated raw values along u (checked against
// central differences inside a cell).
TEST(CameraRefinement, PositionGradientMatchesFiniteDifferences) {
    const RadianceGrid truth = ball_field(12);
    const detail::GridView g = truth.view(false);
    const float d_raw[4] = {0.3f, -1.0f, 0.5f, 2.0f};
    for (const Vec3d u : {Vec3d{0.41, 0.52, 0.37}, Vec3d{0.66, 0.3, 0.58}}) {
        const float uf[3] = {static_cast<float>(u.x), static_cast<float>(u.y),
                             static_cast<float>(u.z)};
        float grad[3];
        detail::position_gradient(g, detail::locate(g, uf), d_raw, grad);
        for (int a = 0; a < 3; ++a) {
            const double h = 1e-3;
            double f[2];
            for (int sgn = 0; sgn < 2; ++sgn) {
                float v[3] = {uf[0], uf[1], uf[2]};
                v[a] += static_cast<float>(sgn == 0 ? h : -h);
                float raw[4];
                detail::interpolate(g, detail::locate(g, v), raw);
                f[sgn] =
                    d_raw[0] * raw[0] + d_raw[1] * raw[1] + d_raw[2] * raw[2] + d_raw[3] * raw[3];
            }
            EXPECT_NEAR(grad[a], (f[0] - f[1]) / (2 * h), 2e-2 * (1.0 + std::fabs(grad[a])))
                << "axis " << a;
        }
    }
}

// Views whose exposure differs (a gain per view and channel, 0.7 to 1.3): with the learned
// exposure the field fits the photos much better, and held-out views at the true exposure are
// reproduced at least as well (the prior keeps the field at the true colours).
TEST(Exposure, PerViewGainsAreFitMuchBetterWithIt) {
    const RadianceGrid truth = ball_field(24);
    Dataset train_set = make_dataset(truth, 24, 24, 0.0);
    const Dataset test_set = make_dataset(truth, 6, 24, 60.0);
    for (std::size_t i = 0; i < train_set.views.size(); ++i) {
        View& v = train_set.views[i];
        for (std::size_t p = 0; p < v.rgb.size(); ++p) {
            const double gain = 1.0 + 0.3 * std::sin(1.7 * static_cast<double>(i) + 2.1 * (p % 3));
            v.rgb[p] = static_cast<float>(v.rgb[p] * gain);
        }
    }
    TrainOptions o = tiny_options();
    const TrainResult plain = train(train_set, o, none);
    o.exposure = true;
    const TrainResult learned = train(train_set, o, none);
    ASSERT_EQ(learned.exposure.size(), train_set.views.size());
    const double plain_test = mean_psnr(plain.grid, test_set);
    const double learned_test = mean_psnr(learned.grid, test_set);
    // The fit: the training views rendered through their learned exposure.
    const auto fit = [&](const TrainResult& r) {
        double sum = 0.0;
        for (std::size_t i = 0; i < train_set.views.size(); ++i) {
            const View& v = train_set.views[i];
            std::vector<float> rgb =
                render_view(r.grid, train_set.intrinsics, v.camera_to_world, train_set.background);
            if (!r.exposure.empty()) {
                for (std::size_t p = 0; p < rgb.size(); ++p) {
                    rgb[p] =
                        (1.0f + r.exposure[i].gain[p % 3]) * rgb[p] + r.exposure[i].bias[p % 3];
                }
            }
            sum += psnr(rgb, v.rgb);
        }
        return sum / static_cast<double>(train_set.views.size());
    };
    const double plain_fit = fit(plain);
    const double learned_fit = fit(learned);
    RecordProperty("plain_fit_psnr", std::to_string(plain_fit));
    RecordProperty("learned_fit_psnr", std::to_string(learned_fit));
    RecordProperty("plain_test_psnr", std::to_string(plain_test));
    RecordProperty("learned_test_psnr", std::to_string(learned_test));
    // Measured: 32.8 dB against 28.7 (fit), 31.3 against 31.0 (held out).
    EXPECT_GT(learned_fit, plain_fit + 3.0) << plain_fit << " " << learned_fit;
    EXPECT_GT(learned_test, plain_test) << plain_test << " " << learned_test;
}

// Perturbed training cameras (rotations of ~1°, eyes moved by ~1.5 % of the distance, focal
// lengths 3 % long): refinement moves the poses and the focal length toward the truth.
TEST(CameraRefinement, PerturbedPosesMoveTowardTheTruth) {
    const RadianceGrid truth = ball_field(24);
    const Dataset exact = make_dataset(truth, 24, 32, 0.0);
    Dataset noisy = exact;
    noisy.intrinsics.fx *= 1.03;
    noisy.intrinsics.fy *= 1.03;
    for (std::size_t i = 0; i < noisy.views.size(); ++i) {
        const double a = static_cast<double>(i);
        const Vec3d w = 0.02 * Vec3d{std::sin(3.1 * a), std::cos(2.3 * a), std::sin(1.3 * a + 1)};
        const Vec3d t = 0.04 * Vec3d{std::cos(1.9 * a), std::sin(2.9 * a + 2), std::cos(0.7 * a)};
        noisy.views[i].camera_to_world = refined_pose(exact.views[i].camera_to_world, w, t);
    }
    std::vector<Pose> truth_poses, before;
    for (std::size_t i = 0; i < exact.views.size(); ++i) {
        truth_poses.push_back(exact.views[i].camera_to_world);
        before.push_back(noisy.views[i].camera_to_world);
    }
    TrainOptions o = tiny_options();
    o.iterations = 600;
    o.refine_poses = true;
    o.refine_focal = true;
    const TrainResult r = train(noisy, o, none);
    ASSERT_EQ(r.poses.size(), noisy.views.size());
    const PoseComparison b = compare_poses(before, truth_poses);
    const PoseComparison a = compare_poses(r.poses, truth_poses);
    RecordProperty("rotation_before_deg", std::to_string(b.median_rotation_error_deg));
    RecordProperty("rotation_after_deg", std::to_string(a.median_rotation_error_deg));
    RecordProperty("center_before", std::to_string(b.median_center_error));
    RecordProperty("center_after", std::to_string(a.median_center_error));
    RecordProperty("focal_scale", std::to_string(r.focal_scale));
    EXPECT_LT(a.median_rotation_error_deg, 0.7 * b.median_rotation_error_deg)
        << b.median_rotation_error_deg << " → " << a.median_rotation_error_deg;
    // Eyes moved across the view are nearly a rotation for a small object (only the parallax
    // over its depth tells them apart), along the view nearly a focal change: less observable.
    EXPECT_LT(a.median_center_error, 0.95 * b.median_center_error)
        << b.median_center_error << " → " << a.median_center_error;
    EXPECT_LT(std::fabs(r.focal_scale * 1.03 - 1.0), 0.7 * 0.03) << r.focal_scale;
}

// Exposure, refinement and the distortion loss: 1 and 2 threads give the same bits; a run resumed
// from a checkpoint the same bits as an uninterrupted one.
TEST(CameraRefinement, IsDeterministicAndResumesBitwise) {
    const RadianceGrid truth = ball_field(16);
    const Dataset ds = make_dataset(truth, 8, 16, 0.0);
    TrainOptions o = tiny_options();
    o.iterations = 60;
    o.resolution = 16;
    o.exposure = true;
    o.refine_poses = true;
    o.refine_focal = true;
    o.distortion = 0.01f;
    const test::ThreadsAndResume runs = test::train_threads_and_resume(ds, o);
    const TrainResult& a = runs.one_thread;
    const TrainResult& b = runs.two_threads;
    const TrainResult& c = runs.resumed;
    for (const TrainResult* r : {&b, &c}) {
        EXPECT_TRUE(
            std::equal(a.grid.params().begin(), a.grid.params().end(), r->grid.params().begin()));
        ASSERT_EQ(a.poses.size(), r->poses.size());
        for (std::size_t i = 0; i < a.poses.size(); ++i) {
            EXPECT_EQ(a.poses[i].m, r->poses[i].m);
        }
        EXPECT_EQ(a.focal_scale, r->focal_scale);
        ASSERT_EQ(a.exposure.size(), r->exposure.size());
        for (std::size_t i = 0; i < a.exposure.size(); ++i) {
            EXPECT_EQ(a.exposure[i].gain, r->exposure[i].gain);
            EXPECT_EQ(a.exposure[i].bias, r->exposure[i].bias);
        }
        EXPECT_EQ(a.final_loss, r->final_loss);
    }
    EXPECT_NE(a.focal_scale, 1.0);
    // A state without the refinement does not resume a run with it.
    o.refine_poses = o.refine_focal = false;
    const std::vector<std::byte> plain_state = test::last_state(ds, o);
    o.refine_poses = true;
    EXPECT_THROW(test::train_resumed(ds, o, plain_state), InvalidInput);
}

}  // namespace
}  // namespace pliant::nerf
