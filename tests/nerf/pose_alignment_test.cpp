// Similarity alignment against transforms built by hand: a known scale, rotation and translation
// applied to random cameras must be recovered, and errors put in by hand must be measured.
#include "pliant/nerf/pose_alignment.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "pliant/core/error.hpp"

namespace pliant::nerf {
namespace {

using Mat3 = std::array<double, 9>;

// Rotation by `angle` radians about the unit axis (Rodrigues' formula).
Mat3 axis_angle(Vec3d axis, double angle) {
    axis = axis / norm(axis);
    const double c = std::cos(angle), s = std::sin(angle), t = 1.0 - c;
    const double x = axis.x, y = axis.y, z = axis.z;
    return {t * x * x + c,     t * x * y - s * z, t * x * z + s * y,
            t * x * y + s * z, t * y * y + c,     t * y * z - s * x,
            t * x * z - s * y, t * y * z + s * x, t * z * z + c};
}

Mat3 multiply(const Mat3& a, const Mat3& b) {
    Mat3 m{};
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            for (int k = 0; k < 3; ++k) {
                m[3 * i + j] += a[3 * i + k] * b[3 * k + j];
            }
        }
    }
    return m;
}

Vec3d apply(const Mat3& r, Vec3d v) {
    return {r[0] * v.x + r[1] * v.y + r[2] * v.z, r[3] * v.x + r[4] * v.y + r[5] * v.z,
            r[6] * v.x + r[7] * v.y + r[8] * v.z};
}

Pose make_pose(const Mat3& r, Vec3d eye, double column_scale = 1.0) {
    Pose p;
    for (int row = 0; row < 3; ++row) {
        for (int c = 0; c < 3; ++c) {
            p.m[4 * row + c] = column_scale * r[3 * row + c];
        }
        p.m[4 * row + 3] = eye[row];
    }
    return p;
}

Mat3 rotation_of(const Pose& p) {
    return {p.m[0], p.m[1], p.m[2], p.m[4], p.m[5], p.m[6], p.m[8], p.m[9], p.m[10]};
}

std::vector<Pose> random_cameras(int n, std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<Pose> poses;
    for (int i = 0; i < n; ++i) {
        const Mat3 r = axis_angle({u(rng), u(rng), u(rng) + 1e-3}, 3.0 * u(rng));
        poses.push_back(make_pose(r, {4.0 * u(rng), 4.0 * u(rng), 2.0 * u(rng)}));
    }
    return poses;
}

// reference = s R estimated + t, applied to whole poses (rotations turn with R).
std::vector<Pose> transformed(const std::vector<Pose>& poses, double s, const Mat3& r, Vec3d t) {
    std::vector<Pose> out;
    for (const Pose& p : poses) {
        out.push_back(make_pose(multiply(r, rotation_of(p)), s * apply(r, p.eye()) + t));
    }
    return out;
}

TEST(PoseAlignment, RecoversAKnownSimilarity) {
    const std::vector<Pose> estimated = random_cameras(20, 7);
    const Mat3 r = axis_angle({0.3, -0.5, 0.8}, 2.1);
    const std::vector<Pose> reference = transformed(estimated, 2.7, r, {1.0, -3.0, 0.5});
    const PoseComparison cmp = compare_poses(estimated, reference);
    EXPECT_NEAR(cmp.estimated_to_reference.scale, 2.7, 1e-10);
    for (int k = 0; k < 9; ++k) {
        EXPECT_NEAR(cmp.estimated_to_reference.rotation[k], r[k], 1e-10) << k;
    }
    EXPECT_NEAR(cmp.estimated_to_reference.translation.x, 1.0, 1e-9);
    EXPECT_NEAR(cmp.estimated_to_reference.translation.y, -3.0, 1e-9);
    EXPECT_NEAR(cmp.estimated_to_reference.translation.z, 0.5, 1e-9);
    EXPECT_LT(cmp.max_rotation_error_deg, 1e-5);
    EXPECT_LT(cmp.max_center_error, 1e-9);
    EXPECT_GT(cmp.center_spread, 1.0);
}

TEST(PoseAlignment, ScaledRotationColumnsAreNormalized) {
    std::vector<Pose> estimated = random_cameras(6, 3);
    const Mat3 r = axis_angle({0.0, 0.0, 1.0}, 0.4);
    const std::vector<Pose> reference = transformed(estimated, 0.5, r, {});
    for (Pose& p : estimated) {
        p = make_pose(rotation_of(p), p.eye(), 3.0);
    }
    EXPECT_LT(compare_poses(estimated, reference).max_rotation_error_deg, 1e-5);
}

TEST(PoseAlignment, MeasuresErrorsPutInByHand) {
    // 8 cameras on a circle; after the similarity, camera 3 is turned by 2° about its own axis and
    // camera 5's centre moved; the rest are exact.
    std::vector<Pose> estimated;
    for (int i = 0; i < 8; ++i) {
        const double a = 2.0 * std::numbers::pi * i / 8.0;
        estimated.push_back(
            make_pose(axis_angle({0, 0, 1}, a), {std::cos(a), std::sin(a), 0.1 * i}));
    }
    const Mat3 r = axis_angle({1.0, 2.0, 3.0}, 0.7);
    std::vector<Pose> reference = transformed(estimated, 10.0, r, {5.0, 5.0, 5.0});
    const Mat3 turned = multiply(rotation_of(reference[3]),
                                 axis_angle({0.0, 1.0, 0.0}, 2.0 * std::numbers::pi / 180));
    reference[3] = make_pose(turned, reference[3].eye());
    const PoseComparison cmp = compare_poses(estimated, reference);
    EXPECT_NEAR(cmp.max_rotation_error_deg, 2.0, 1e-6);
    EXPECT_NEAR(cmp.rotation_error_deg[3], 2.0, 1e-6);
    EXPECT_NEAR(cmp.median_rotation_error_deg, 0.0, 1e-6);
    EXPECT_LT(cmp.max_center_error, 1e-8);
    EXPECT_NEAR(rotation_angle_deg(reference[3], reference[3]), 0.0, 1e-6);

    // A centre moved by 0.5 (reference units): the least-squares fit spreads it, but the
    // largest error stays on that camera and is a large part of 0.5.
    std::vector<Pose> moved = transformed(estimated, 10.0, r, {5.0, 5.0, 5.0});
    moved[5].m[3] += 0.5;
    const PoseComparison cm = compare_poses(estimated, moved);
    const auto worst = std::max_element(cm.center_error.begin(), cm.center_error.end());
    EXPECT_EQ(worst - cm.center_error.begin(), 5);
    EXPECT_GT(cm.max_center_error, 0.3);
    EXPECT_LT(cm.max_center_error, 0.5);
    EXPECT_NEAR(cm.max_center_error_relative(), cm.max_center_error / cm.center_spread, 1e-15);
}

TEST(PoseAlignment, RejectsDegenerateInput) {
    const std::vector<Vec3d> line{{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
    const std::vector<Vec3d> line2{{1, 0, 0}, {3, 2, 2}, {5, 4, 4}, {7, 6, 6}};
    EXPECT_THROW(align_similarity(line, line2), InvalidInput);
    const std::vector<Vec3d> two{{0, 0, 0}, {1, 0, 0}};
    EXPECT_THROW(align_similarity(two, two), InvalidInput);
    const std::vector<Vec3d> same{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
    const std::vector<Vec3d> tri{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    EXPECT_THROW(align_similarity(same, tri), InvalidInput);
    EXPECT_THROW(align_similarity(tri, line), InvalidInput);
    std::vector<Vec3d> nan = tri;
    nan[1].y = std::nan("");
    try {
        align_similarity(nan, tri);
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("point pair 1"), std::string::npos) << e.what();
    }
    // A mirror image is not a similarity: the best proper rotation leaves residuals, never a
    // reflection.
    const std::vector<Vec3d> pts{{1, 0, 0}, {0, 2, 0}, {0, 0, 3}, {1, 1, 1}};
    std::vector<Vec3d> mirrored = pts;
    for (Vec3d& p : mirrored) {
        p.x = -p.x;
    }
    try {
        const Similarity sim = align_similarity(pts, mirrored);
        const auto& m = sim.rotation;
        const double det = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) +
                           m[2] * (m[3] * m[7] - m[4] * m[6]);
        EXPECT_NEAR(det, 1.0, 1e-9);
    } catch (const InvalidInput&) {
        SUCCEED();  // a non-positive best scale is reported, also fine
    }
}

}  // namespace
}  // namespace pliant::nerf
