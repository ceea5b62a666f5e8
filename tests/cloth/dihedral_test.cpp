#include "pliant/cloth/dihedral.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace pliant::cloth {
namespace {

double component(const Vec3d& v, int axis) {
    return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

TEST(DihedralAngle, FlatPairIsZeroAndFoldsHaveKnownAngles) {
    // Shared edge along x; A's apex at -y, B's apex at +y.
    const Vec3d x2{-1.0, 0.0, 0.0};
    const Vec3d x3{1.0, 0.0, 0.0};
    EXPECT_NEAR(dihedral_angle_value({0.0, -1.0, 0.0}, {0.0, 1.0, 0.0}, x2, x3), 0.0, 1e-15);
    // B folded up by 90 degrees, then down by 90 degrees: opposite signs, magnitude π/2.
    const double up = dihedral_angle_value({0.0, -1.0, 0.0}, {0.0, 0.0, 1.0}, x2, x3);
    const double down = dihedral_angle_value({0.0, -1.0, 0.0}, {0.0, 0.0, -1.0}, x2, x3);
    EXPECT_NEAR(std::fabs(up), std::numbers::pi / 2.0, 1e-12);
    EXPECT_NEAR(up, -down, 1e-12);
}

TEST(DihedralAngle, GradientMatchesFiniteDifferencesAndSumsToZero) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
    int checked = 0;
    for (int trial = 0; trial < 500; ++trial) {
        Vec3d x[4];
        for (Vec3d& p : x) {
            p = {coordinate(rng), coordinate(rng), coordinate(rng)};
        }
        const DihedralAngle angle = dihedral_angle(x[0], x[1], x[2], x[3]);
        ASSERT_TRUE(angle.is_valid);
        if (std::fabs(std::fabs(angle.angle) - std::numbers::pi) < 0.05) {
            continue;  // next to the ±π wrap the finite difference jumps
        }
        Vec3d sum{0.0, 0.0, 0.0};
        for (int k = 0; k < 4; ++k) {
            sum += angle.gradient[static_cast<std::size_t>(k)];
            for (int axis = 0; axis < 3; ++axis) {
                constexpr double STEP = 1e-6;
                Vec3d plus[4] = {x[0], x[1], x[2], x[3]};
                Vec3d minus[4] = {x[0], x[1], x[2], x[3]};
                (axis == 0 ? plus[k].x : axis == 1 ? plus[k].y : plus[k].z) += STEP;
                (axis == 0 ? minus[k].x : axis == 1 ? minus[k].y : minus[k].z) -= STEP;
                const double numeric =
                    (dihedral_angle_value(plus[0], plus[1], plus[2], plus[3]) -
                     dihedral_angle_value(minus[0], minus[1], minus[2], minus[3])) /
                    (2.0 * STEP);
                const double analytic =
                    component(angle.gradient[static_cast<std::size_t>(k)], axis);
                EXPECT_NEAR(analytic, numeric, 1e-5 * (1.0 + std::fabs(numeric)))
                    << "trial " << trial << " vertex " << k << " axis " << axis;
            }
        }
        EXPECT_NEAR(norm(sum), 0.0, 1e-9);
        ++checked;
    }
    EXPECT_GT(checked, 400);
}

TEST(DihedralAngle, DegenerateInputIsInvalid) {
    const Vec3d x2{-1.0, 0.0, 0.0};
    const Vec3d x3{1.0, 0.0, 0.0};
    // A's apex on the shared edge's line: zero area.
    EXPECT_FALSE(dihedral_angle({0.5, 0.0, 0.0}, {0.0, 1.0, 0.0}, x2, x3).is_valid);
    // Zero-length shared edge.
    EXPECT_FALSE(dihedral_angle({0.0, -1.0, 0.0}, {0.0, 1.0, 0.0}, x2, x2).is_valid);
}

}  // namespace
}  // namespace pliant::cloth
