// Camera refinement's parameterisation (nerf::train with refine_poses, trainer.hpp) and how a
// refinement learned on the training views is carried to held-out views.
//
//   - A view's delta (ω, τ): ω ∈ so(3) in radians (axis · angle, world axes), τ a displacement
//     of the eye in world units. The refined camera-to-world pose has the rotation
//     exp(ω) R (Rodrigues' formula; the columns, and so any scale R carries, rotate together)
//     and the eye t + τ: the camera turns about its own eye.
//   - Held-out views: the refined training poses differ from the input ones by per-view
//     corrections and by a shared drift of the whole rig (the field may move with it; nothing
//     pins the world frame). transfer_refinement fits the similarity from the input training
//     eyes to the refined ones (align_similarity, pose_alignment.hpp) and applies it to the
//     held-out poses (rotation R_s R, eye s R_s t + t_s), so they follow the drift.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "pliant/nerf/dataset.hpp"

namespace pliant::nerf {

// exp(ω) as a row-major 3 × 3 rotation (the identity for |ω| < 1e-12; Taylor terms near 0).
std::array<double, 9> rotation_from_axis_angle(const Vec3d& omega);

// The pose with delta (ω, τ) applied (see the header comment).
Pose refined_pose(const Pose& pose, const Vec3d& omega, const Vec3d& tau);

// The held-out `poses` moved by the similarity from `original` training eyes to `refined` ones.
// Returns `poses` unchanged when there are fewer than 3 training views or their eyes are
// collinear (the similarity is then undetermined); InvalidInput when the spans' sizes differ.
std::vector<Pose> transfer_refinement(std::span<const Pose> original, std::span<const Pose> refined,
                                      std::span<const Pose> poses);

}  // namespace pliant::nerf
