// Rigid motion from keyframes: how pinned vertices and obstacles move over a cloth scene.
//
// A Motion maps a point p given at its rest placement (time 0 of the scene) to where it is at
// time t (seconds):
//   p(t) = R(θ(t)) (p − pivot) + pivot + d(t),
// where θ(t) (degrees, rotation about x, then y, then z, right-handed, as the scene's transform)
// and d(t) (metres) interpolate the keyframes linearly in time and hold the first / last
// keyframe's values before / after them. Angles are interpolated as numbers, so a keyframe pair
// (0, 0, 0) → (0, 0, 720) turns two full turns about z. A Motion without keyframes is the
// identity. Keyframe times must be finite and strictly increasing (io checks scene files;
// is_valid() checks the rest).
//
// Units: seconds, metres, degrees.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "pliant/core/vec3.hpp"

namespace pliant::cloth {

struct Keyframe {
    double time = 0.0;                    // s
    Vec3d translate{0.0, 0.0, 0.0};       // m
    Vec3d rotate_degrees{0.0, 0.0, 0.0};  // about x, then y, then z
};

// R = Rz · Ry · Rx for angles in degrees: rotates about x first. Rows of a 3×3 matrix.
struct Rotation {
    Vec3d row[3] = {{1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};

    static Rotation from_degrees(const Vec3d& degrees) {
        const double to_radians = std::numbers::pi / 180.0;
        const double cx = std::cos(degrees.x * to_radians);
        const double sx = std::sin(degrees.x * to_radians);
        const double cy = std::cos(degrees.y * to_radians);
        const double sy = std::sin(degrees.y * to_radians);
        const double cz = std::cos(degrees.z * to_radians);
        const double sz = std::sin(degrees.z * to_radians);
        Rotation r;
        r.row[0] = {cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx};
        r.row[1] = {sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx};
        r.row[2] = {-sy, cy * sx, cy * cx};
        return r;
    }
    Vec3d apply(const Vec3d& p) const { return {dot(row[0], p), dot(row[1], p), dot(row[2], p)}; }
    // The inverse rotation (the transpose).
    Vec3d apply_inverse(const Vec3d& p) const { return row[0] * p.x + row[1] * p.y + row[2] * p.z; }
};

// The motion's pose at one time: p ↦ rotation (p − pivot) + pivot + translate.
struct Pose {
    Rotation rotation;
    Vec3d pivot{0.0, 0.0, 0.0};
    Vec3d translate{0.0, 0.0, 0.0};

    Vec3d apply(const Vec3d& p) const { return rotation.apply(p - pivot) + pivot + translate; }
    Vec3d apply_inverse(const Vec3d& p) const {
        return rotation.apply_inverse(p - pivot - translate) + pivot;
    }
};

struct Motion {
    Vec3d pivot{0.0, 0.0, 0.0};  // m, the centre of rotation
    std::vector<Keyframe> keyframes;

    bool is_static() const { return keyframes.empty(); }

    bool is_valid() const {
        for (std::size_t k = 0; k < keyframes.size(); ++k) {
            if (!std::isfinite(keyframes[k].time) || !is_finite(keyframes[k].translate) ||
                !is_finite(keyframes[k].rotate_degrees) ||
                (k > 0 && !(keyframes[k].time > keyframes[k - 1].time))) {
                return false;
            }
        }
        return is_finite(pivot);
    }

    // True when some keyframe rotates (then only obstacles that can rotate may use it).
    bool rotates() const {
        return std::any_of(keyframes.begin(), keyframes.end(), [](const Keyframe& k) {
            return k.rotate_degrees != Vec3d{0.0, 0.0, 0.0};
        });
    }

    // The farthest a point within `reach` metres of the pivot travels in one step of h seconds
    // (h > 0) along this motion, and when that step starts (s). Over keyframes a → b a point's
    // path is at most |Δd| + r · (|Δθx| + |Δθy| + |Δθz|) (angles in radians: each rotation about
    // one axis moves a point at most its angle times its distance from the pivot, and rotations
    // keep lengths), spread evenly over b.time − a.time, so one step covers at most
    // min(1, h / (b.time − a.time)) of it. 0 (at time 0) for a motion without keyframes.
    struct FastestStep {
        double distance = 0.0;  // m
        double time = 0.0;      // s, the keyframe segment's start
    };
    FastestStep fastest_step(double reach, double h) const {
        FastestStep fastest;
        const double to_radians = std::numbers::pi / 180.0;
        for (std::size_t k = 1; k < keyframes.size(); ++k) {
            const Keyframe& a = keyframes[k - 1];
            const Keyframe& b = keyframes[k];
            const Vec3d turn = b.rotate_degrees - a.rotate_degrees;
            const double path =
                norm(b.translate - a.translate) +
                reach * to_radians * (std::fabs(turn.x) + std::fabs(turn.y) + std::fabs(turn.z));
            const double step = path * std::min(1.0, h / (b.time - a.time));
            if (step > fastest.distance) {
                fastest = {step, a.time};
            }
        }
        return fastest;
    }

    Pose pose(double t) const {
        Pose pose;
        pose.pivot = pivot;
        if (keyframes.empty()) {
            return pose;
        }
        Keyframe at = keyframes.front();
        if (t >= keyframes.back().time) {
            at = keyframes.back();
        } else if (t > keyframes.front().time) {
            const auto next =
                std::upper_bound(keyframes.begin(), keyframes.end(), t,
                                 [](double time, const Keyframe& k) { return time < k.time; });
            const Keyframe& b = *next;
            const Keyframe& a = *(next - 1);
            const double s = (t - a.time) / (b.time - a.time);
            at.translate = a.translate + (b.translate - a.translate) * s;
            at.rotate_degrees = a.rotate_degrees + (b.rotate_degrees - a.rotate_degrees) * s;
        }
        pose.rotation = Rotation::from_degrees(at.rotate_degrees);
        pose.translate = at.translate;
        return pose;
    }
};

// A motion followed over time: the pose at the current time and at the previous one, from which
// the velocity of a point on the moving body follows.
struct MotionState {
    Motion motion;
    Pose pose;           // at the current time
    Pose previous_pose;  // at the previous advance() (the same until then)

    MotionState() = default;
    MotionState(Motion m, double t)
        : motion(std::move(m)), pose(motion.pose(t)), previous_pose(pose) {}

    void advance(double t) {
        if (!motion.is_static()) {
            previous_pose = pose;
            pose = motion.pose(t);
        }
    }
    // How far the body's point now at x moved since the previous pose (m); 0 for a static body.
    Vec3d surface_displacement(const Vec3d& x) const {
        if (motion.is_static()) {
            return {0.0, 0.0, 0.0};
        }
        return x - previous_pose.apply(pose.apply_inverse(x));
    }
};

}  // namespace pliant::cloth
