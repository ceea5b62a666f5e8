// Similarity alignment of two sets of camera poses, and the errors that remain after it: how far
// recovered poses (COLMAP's, up to an unknown scale, rotation and translation of the world) are
// from a reference (a renderer's ground truth, or another reconstruction).
//
// align_similarity(source, target): the scale s > 0, rotation R and translation t minimizing
//   Σ_i |target_i − (s R source_i + t)|²
// over #N point pairs (Umeyama 1991, "Least-squares estimation of transformation parameters
// between two point patterns", eq. 40–42). R is found as the unit quaternion of the largest
// eigenvalue of Horn's symmetric 4 × 4 matrix (Horn 1987, "Closed-form solution of absolute
// orientation using unit quaternions", sec. 4), which is the same optimum and is a proper
// rotation by construction (no reflection case); s = Σ (target_i − t̄)·R(source_i − s̄) /
// Σ |source_i − s̄|² and t = t̄ − s R s̄, where s̄, t̄ are the centroids.
// InvalidInput when the spans differ in length, hold fewer than 3 points or a NaN/Inf, or when
// either set is (numerically) collinear — the rotation about that line is then undetermined
// (the two largest eigenvalues of Horn's matrix within 1e-9 of its norm, or a point spread below
// 1e-12 of the coordinates' magnitude).
//
// compare_poses(estimated, reference): aligns the estimated camera centres (eyes) to the
// reference ones with align_similarity, then for every camera i:
//   - rotation error: the angle of R_ref,i^T · (R · R_est,i) in degrees, where R_·,i are the
//     camera-to-world rotations with their columns normalized (a Pose may carry a scale);
//   - centre error: |s R c_est,i + t − c_ref,i| in the reference's units.
// The spread of the reference centres is their RMS distance from their centroid; centre errors
// are also given relative to it. Poses are camera-to-world in one axis convention for both sets
// (the rotation error is independent of that convention only when both use the same one).
// Same preconditions as align_similarity on the eyes.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "pliant/core/vec3.hpp"
#include "pliant/nerf/dataset.hpp"

namespace pliant::nerf {

struct Similarity {
    double scale = 1.0;
    std::array<double, 9> rotation{1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major 3 × 3
    Vec3d translation{};

    Vec3d rotate(Vec3d v) const;
    Vec3d apply(Vec3d p) const { return scale * rotate(p) + translation; }
};

Similarity align_similarity(std::span<const Vec3d> source, std::span<const Vec3d> target);

struct PoseComparison {
    Similarity estimated_to_reference;
    std::vector<double> rotation_error_deg;  // #N, per camera
    std::vector<double> center_error;        // #N, per camera, reference units
    double center_spread = 0.0;              // RMS distance of the reference eyes to their centroid
    double median_rotation_error_deg = 0.0;
    double max_rotation_error_deg = 0.0;
    double median_center_error = 0.0;
    double max_center_error = 0.0;
    // The centre errors divided by center_spread.
    double median_center_error_relative() const { return median_center_error / center_spread; }
    double max_center_error_relative() const { return max_center_error / center_spread; }
};

PoseComparison compare_poses(std::span<const Pose> estimated, std::span<const Pose> reference);

// The angle in degrees of the rotation between two camera-to-world rotations (columns normalized
// first): acos((trace(A^T B) − 1) / 2), clamped to [0, 180].
double rotation_angle_deg(const Pose& a, const Pose& b);

}  // namespace pliant::nerf
