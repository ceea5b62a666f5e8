#include "pliant/nerf/camera_refinement.hpp"

#include <fmt/format.h>

#include <cmath>

#include "pliant/core/error.hpp"
#include "pliant/nerf/pose_alignment.hpp"

namespace pliant::nerf {

std::array<double, 9> rotation_from_axis_angle(const Vec3d& omega) {
    const double theta2 = dot(omega, omega);
    const double theta = std::sqrt(theta2);
    // R = I + a [ω]x + b [ω]x², a = sin θ / θ, b = (1 − cos θ) / θ².
    double a = 1.0, b = 0.5;
    if (theta > 1e-4) {
        a = std::sin(theta) / theta;
        b = (1.0 - std::cos(theta)) / theta2;
    } else {
        a = 1.0 - theta2 / 6.0;
        b = 0.5 - theta2 / 24.0;
    }
    const double x = omega.x, y = omega.y, z = omega.z;
    // [ω]x and [ω]x² = ω ωᵀ − θ² I.
    const std::array<double, 9> k{0, -z, y, z, 0, -x, -y, x, 0};
    const std::array<double, 9> k2{x * x - theta2, x * y, x * z, x * y,         y * y - theta2,
                                   y * z,          x * z, y * z, z * z - theta2};
    std::array<double, 9> r{};
    for (int i = 0; i < 9; ++i) {
        r[i] = (i % 4 == 0 ? 1.0 : 0.0) + a * k[i] + b * k2[i];
    }
    return r;
}

Pose refined_pose(const Pose& pose, const Vec3d& omega, const Vec3d& tau) {
    const std::array<double, 9> q = rotation_from_axis_angle(omega);
    Pose out;
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) {
            double v = 0.0;
            for (int k = 0; k < 3; ++k) {
                v += q[3 * r + k] * pose.m[4 * k + c];
            }
            out.m[4 * r + c] = v;
        }
    }
    const Vec3d eye = pose.eye() + tau;
    out.m[3] = eye.x;
    out.m[7] = eye.y;
    out.m[11] = eye.z;
    return out;
}

std::vector<Pose> transfer_refinement(std::span<const Pose> original, std::span<const Pose> refined,
                                      std::span<const Pose> poses) {
    if (original.size() != refined.size()) {
        throw InvalidInput(fmt::format("transfer_refinement: {} original and {} refined poses",
                                       original.size(), refined.size()));
    }
    std::vector<Pose> out(poses.begin(), poses.end());
    if (original.size() < 3) {
        return out;
    }
    std::vector<Vec3d> from, to;
    for (std::size_t i = 0; i < original.size(); ++i) {
        from.push_back(original[i].eye());
        to.push_back(refined[i].eye());
    }
    Similarity s;
    try {
        s = align_similarity(from, to);
    } catch (const InvalidInput&) {
        return out;  // collinear eyes: no similarity to carry
    }
    for (Pose& p : out) {
        for (int c = 0; c < 3; ++c) {
            const Vec3d axis = s.rotate(p.axis(c));
            p.m[c] = axis.x;
            p.m[4 + c] = axis.y;
            p.m[8 + c] = axis.z;
        }
        const Vec3d eye = s.apply(p.eye());
        p.m[3] = eye.x;
        p.m[7] = eye.y;
        p.m[11] = eye.z;
    }
    return out;
}

}  // namespace pliant::nerf
