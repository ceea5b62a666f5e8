#include "pliant/cloth/motion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace pliant::cloth {
namespace {

void expect_near(const Vec3d& a, const Vec3d& b, double tolerance = 1e-12) {
    EXPECT_NEAR(a.x, b.x, tolerance);
    EXPECT_NEAR(a.y, b.y, tolerance);
    EXPECT_NEAR(a.z, b.z, tolerance);
}

// Rotations about single axes, right-handed: x turns y into z, y turns z into x, z turns x into y;
// and the order: about x first, then z.
TEST(Motion, RotationIsRightHandedAndAppliesXThenYThenZ) {
    expect_near(Rotation::from_degrees({90, 0, 0}).apply({0, 1, 0}), {0, 0, 1});
    expect_near(Rotation::from_degrees({0, 90, 0}).apply({0, 0, 1}), {1, 0, 0});
    expect_near(Rotation::from_degrees({0, 0, 90}).apply({1, 0, 0}), {0, 1, 0});
    // x by 90° takes y to z; z by 90° then leaves z alone.
    expect_near(Rotation::from_degrees({90, 0, 90}).apply({0, 1, 0}), {0, 0, 1});
    // x by 90° takes z to -y; z by 90° takes -y to x.
    expect_near(Rotation::from_degrees({90, 0, 90}).apply({0, 0, 1}), {1, 0, 0});
    const Rotation r = Rotation::from_degrees({10, -35, 123});
    const Vec3d p{0.3, -1.2, 2.5};
    expect_near(r.apply_inverse(r.apply(p)), p);
    EXPECT_NEAR(norm(r.apply(p)), norm(p), 1e-12);
}

TEST(Motion, InterpolatesKeyframesAndHoldsTheEnds) {
    Motion motion;
    motion.pivot = {1.0, 0.0, 0.0};
    motion.keyframes = {Keyframe{1.0, {0, 0, 0}, {0, 0, 0}}, Keyframe{3.0, {0, 0, 2}, {0, 0, 360}}};
    EXPECT_FALSE(motion.is_static());
    EXPECT_TRUE(motion.rotates());
    EXPECT_TRUE(motion.is_valid());
    const Vec3d p{2.0, 0.0, 0.0};               // 1 m from the pivot along x
    expect_near(motion.pose(0.0).apply(p), p);  // before the first keyframe: held
    expect_near(motion.pose(1.0).apply(p), p);
    expect_near(motion.pose(1.5).apply(p), {1.0, 1.0, 0.5});   // 90°, z + 0.5
    expect_near(motion.pose(2.0).apply(p), {0.0, 0.0, 1.0});   // 180°
    expect_near(motion.pose(3.0).apply(p), {2.0, 0.0, 2.0});   // a full turn
    expect_near(motion.pose(10.0).apply(p), {2.0, 0.0, 2.0});  // after the last: held
    const Pose pose = motion.pose(2.3);
    expect_near(pose.apply_inverse(pose.apply(p)), p);
    // Angles are interpolated as numbers: 720° is two turns, not none.
    Motion two_turns;
    two_turns.keyframes = {Keyframe{0.0, {}, {}}, Keyframe{1.0, {}, {0, 0, 720}}};
    expect_near(two_turns.pose(0.125).apply({1, 0, 0}), {0, 1, 0});  // 90°
}

TEST(Motion, EmptyIsIdentityAndBadKeyframesAreInvalid) {
    const Motion still;
    EXPECT_TRUE(still.is_static());
    EXPECT_FALSE(still.rotates());
    expect_near(still.pose(5.0).apply({1, 2, 3}), {1, 2, 3});
    Motion unordered;
    unordered.keyframes = {Keyframe{1.0, {}, {}}, Keyframe{1.0, {}, {}}};
    EXPECT_FALSE(unordered.is_valid());
    Motion nan;
    nan.keyframes = {Keyframe{0.0, {std::nan(""), 0, 0}, {}}};
    EXPECT_FALSE(nan.is_valid());
}

TEST(Motion, FastestStepBoundsThePathOfOneStep) {
    // 1.6 m in 1 ms, then held: a 0.5 ms step covers half of it, a 2 ms step all of it.
    Motion jump;
    jump.keyframes = {Keyframe{0.0, {}, {}}, Keyframe{0.001, {0.0, 1.6, 0.0}, {}}};
    EXPECT_DOUBLE_EQ(jump.fastest_step(10.0, 0.0005).distance, 0.8);
    EXPECT_DOUBLE_EQ(jump.fastest_step(10.0, 0.002).distance, 1.6);
    // Two segments: the faster one counts, with its start time.
    Motion two;
    two.keyframes = {Keyframe{0.0, {}, {}}, Keyframe{1.0, {0.1, 0.0, 0.0}, {}},
                     Keyframe{1.5, {0.1, 0.0, 1.1}, {}}};
    const Motion::FastestStep fastest = two.fastest_step(0.0, 0.01);
    EXPECT_NEAR(fastest.distance, 0.022, 1e-15);  // 1.1 m in 0.5 s
    EXPECT_DOUBLE_EQ(fastest.time, 1.0);
    // A turn: a point 0.5 m from the pivot on two turns in 3 s moves 0.5 · 4π / 3 m/s; the true
    // chord of one step is just below that bound.
    Motion turn;
    turn.keyframes = {Keyframe{0.0, {}, {}}, Keyframe{3.0, {}, {0.0, 0.0, 720.0}}};
    const double h = 1.0 / 960.0;
    const double bound = turn.fastest_step(0.5, h).distance;
    EXPECT_NEAR(bound, 0.5 * 4.0 * std::numbers::pi / 3.0 * h, 1e-12);
    const Vec3d p{0.5, 0.0, 0.0};
    const double chord = norm(turn.pose(1.0 + h).apply(p) - turn.pose(1.0).apply(p));
    EXPECT_LE(chord, bound);
    EXPECT_GT(chord, 0.999 * bound);
    // No keyframes, or one: no motion.
    EXPECT_EQ(Motion{}.fastest_step(1.0, 1.0).distance, 0.0);
}

}  // namespace
}  // namespace pliant::cloth
