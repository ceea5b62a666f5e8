#include "pliant/nerf/pose_alignment.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pliant/core/error.hpp"

namespace pliant::nerf {
namespace {

using Mat3 = std::array<double, 9>;
using Mat4 = std::array<std::array<double, 4>, 4>;

// Eigen-decomposition of a symmetric 4 × 4 matrix by cyclic Jacobi rotations (Golub & Van Loan,
// "Matrix Computations", sec. 8.5.2). On return `a` is diagonal (the eigenvalues) and the columns
// of `v` are the eigenvectors. Converges quadratically; 50 sweeps is far more than needed.
void jacobi_eigen(Mat4& a, Mat4& v) {
    for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
            v[i][j] = i == j ? 1.0 : 0.0;
        }
    }
    for (int sweep = 0; sweep < 50; ++sweep) {
        double off = 0.0, total = 0.0;
        for (int i = 0; i < 4; ++i) {
            for (int j = 0; j < 4; ++j) {
                total += a[i][j] * a[i][j];
                if (i != j) {
                    off += a[i][j] * a[i][j];
                }
            }
        }
        if (off <= 1e-30 * total || total == 0.0) {
            return;
        }
        for (int p = 0; p < 3; ++p) {
            for (int q = p + 1; q < 4; ++q) {
                if (a[p][q] == 0.0) {
                    continue;
                }
                const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                const double t = (theta >= 0.0 ? 1.0 : -1.0) /
                                 (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0);
                const double s = t * c;
                for (int k = 0; k < 4; ++k) {  // A ← A J (columns p, q)
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 4; ++k) {  // A ← J^T A (rows p, q)
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 4; ++k) {  // V ← V J
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
}

// The rotation matrix of the unit quaternion (w, x, y, z).
Mat3 rotation_from_quaternion(double w, double x, double y, double z) {
    return {w * w + x * x - y * y - z * z, 2 * (x * y - w * z),
            2 * (x * z + w * y),           2 * (x * y + w * z),
            w * w - x * x + y * y - z * z, 2 * (y * z - w * x),
            2 * (x * z - w * y),           2 * (y * z + w * x),
            w * w - x * x - y * y + z * z};
}

// The camera-to-world rotation of a pose with its columns normalized.
Mat3 unit_rotation(const Pose& pose) {
    Mat3 r{};
    for (int c = 0; c < 3; ++c) {
        const Vec3d axis = pose.axis(c);
        const double n = norm(axis);
        for (int row = 0; row < 3; ++row) {
            r[3 * row + c] = n > 0.0 ? axis[row] / n : 0.0;
        }
    }
    return r;
}

Mat3 multiply(const Mat3& a, const Mat3& b) {
    Mat3 m{};
    for (std::size_t i = 0; i < 3; ++i) {
        for (std::size_t j = 0; j < 3; ++j) {
            m[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
        }
    }
    return m;
}

double angle_between(const Mat3& a, const Mat3& b) {
    double trace = 0.0;  // trace(A^T B)
    for (int k = 0; k < 9; ++k) {
        trace += a[k] * b[k];
    }
    const double c = std::clamp((trace - 1.0) / 2.0, -1.0, 1.0);
    return std::acos(c) * 180.0 / std::numbers::pi;
}

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

Vec3d centroid(std::span<const Vec3d> points) {
    Vec3d sum{};
    for (const Vec3d& p : points) {
        sum += p;
    }
    return sum / static_cast<double>(points.size());
}

}  // namespace

Vec3d Similarity::rotate(Vec3d v) const {
    const Mat3& r = rotation;
    return {r[0] * v.x + r[1] * v.y + r[2] * v.z, r[3] * v.x + r[4] * v.y + r[5] * v.z,
            r[6] * v.x + r[7] * v.y + r[8] * v.z};
}

Similarity align_similarity(std::span<const Vec3d> source, std::span<const Vec3d> target) {
    if (source.size() != target.size()) {
        throw InvalidInput(fmt::format("align_similarity: source has {} points, target has {}",
                                       source.size(), target.size()));
    }
    if (source.size() < 3) {
        throw InvalidInput(
            fmt::format("align_similarity: {} point pairs, expected at least 3 (not collinear)",
                        source.size()));
    }
    for (std::size_t i = 0; i < source.size(); ++i) {
        if (!is_finite(source[i]) || !is_finite(target[i])) {
            throw InvalidInput(fmt::format(
                "align_similarity: point pair {} is not finite: ({}, {}, {}) → ({}, "
                "{}, {})",
                i, source[i].x, source[i].y, source[i].z, target[i].x, target[i].y, target[i].z));
        }
    }

    // Step 1: centroids, spreads and the cross-covariance S = Σ a_i b_i^T of the centred points.
    const Vec3d mean_source = centroid(source), mean_target = centroid(target);
    double source_var = 0.0, target_var = 0.0, magnitude = 0.0;
    Mat3 s{};
    for (std::size_t i = 0; i < source.size(); ++i) {
        const Vec3d a = source[i] - mean_source, b = target[i] - mean_target;
        source_var += squared_norm(a);
        target_var += squared_norm(b);
        magnitude = std::max({magnitude, squared_norm(source[i]), squared_norm(target[i])});
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                s[3 * r + c] += a[r] * b[c];
            }
        }
    }
    if (source_var <= 1e-24 * magnitude || target_var <= 1e-24 * magnitude || source_var == 0.0 ||
        target_var == 0.0) {
        throw InvalidInput(fmt::format(
            "align_similarity: the {} points of the {} set all coincide", source.size(),
            source_var <= 1e-24 * magnitude || source_var == 0.0 ? "source" : "target"));
    }

    // Step 2: Horn's matrix; its top eigenvector is the rotation's quaternion (w, x, y, z).
    const double sxx = s[0], sxy = s[1], sxz = s[2], syx = s[3], syy = s[4], syz = s[5], szx = s[6],
                 szy = s[7], szz = s[8];
    Mat4 n{{{sxx + syy + szz, syz - szy, szx - sxz, sxy - syx},
            {syz - szy, sxx - syy - szz, sxy + syx, szx + sxz},
            {szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy},
            {sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz}}};
    double n_norm = 0.0;
    for (const auto& row : n) {
        for (double x : row) {
            n_norm = std::max(n_norm, std::abs(x));
        }
    }
    Mat4 v{};
    jacobi_eigen(n, v);
    std::array<int, 4> order{0, 1, 2, 3};
    std::sort(order.begin(), order.end(), [&](int i, int j) { return n[i][i] > n[j][j]; });
    if (n[order[0]][order[0]] - n[order[1]][order[1]] <= 1e-9 * n_norm) {
        throw InvalidInput(fmt::format(
            "align_similarity: the {} points are collinear, so the rotation about their line is "
            "undetermined",
            source.size()));
    }
    const int top = order[0];
    double qw = v[0][top], qx = v[1][top], qy = v[2][top], qz = v[3][top];
    const double qn = std::sqrt(qw * qw + qx * qx + qy * qy + qz * qz);
    qw /= qn;
    qx /= qn;
    qy /= qn;
    qz /= qn;

    // Step 3: the least-squares scale for that rotation, then the translation.
    Similarity result;
    result.rotation = rotation_from_quaternion(qw, qx, qy, qz);
    double dot_sum = 0.0;
    for (std::size_t i = 0; i < source.size(); ++i) {
        dot_sum += dot(target[i] - mean_target, result.rotate(source[i] - mean_source));
    }
    result.scale = dot_sum / source_var;
    if (!(result.scale > 0.0)) {
        throw InvalidInput(fmt::format(
            "align_similarity: the best scale is {} (not positive): the point sets are not related "
            "by a similarity",
            result.scale));
    }
    result.translation = mean_target - result.scale * result.rotate(mean_source);
    return result;
}

double rotation_angle_deg(const Pose& a, const Pose& b) {
    return angle_between(unit_rotation(a), unit_rotation(b));
}

PoseComparison compare_poses(std::span<const Pose> estimated, std::span<const Pose> reference) {
    if (estimated.size() != reference.size()) {
        throw InvalidInput(fmt::format("compare_poses: {} estimated poses, {} reference poses",
                                       estimated.size(), reference.size()));
    }
    std::vector<Vec3d> source, target;
    source.reserve(estimated.size());
    target.reserve(reference.size());
    for (std::size_t i = 0; i < estimated.size(); ++i) {
        source.push_back(estimated[i].eye());
        target.push_back(reference[i].eye());
    }
    PoseComparison result;
    result.estimated_to_reference = align_similarity(source, target);
    const Similarity& sim = result.estimated_to_reference;

    const Vec3d mean_target = centroid(target);
    double spread2 = 0.0;
    for (const Vec3d& p : target) {
        spread2 += squared_norm(p - mean_target);
    }
    result.center_spread = std::sqrt(spread2 / static_cast<double>(target.size()));

    for (std::size_t i = 0; i < estimated.size(); ++i) {
        const Mat3 aligned = multiply(sim.rotation, unit_rotation(estimated[i]));
        result.rotation_error_deg.push_back(angle_between(unit_rotation(reference[i]), aligned));
        result.center_error.push_back(norm(sim.apply(source[i]) - target[i]));
    }
    result.median_rotation_error_deg = median(result.rotation_error_deg);
    result.max_rotation_error_deg =
        *std::max_element(result.rotation_error_deg.begin(), result.rotation_error_deg.end());
    result.median_center_error = median(result.center_error);
    result.max_center_error =
        *std::max_element(result.center_error.begin(), result.center_error.end());
    return result;
}

}  // namespace pliant::nerf
