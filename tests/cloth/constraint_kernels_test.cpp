#include "pliant/cloth/detail/constraint_kernels.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "pliant/cloth/dihedral.hpp"
#include "pliant/core/simd_dispatch.hpp"

namespace pliant::cloth::detail {
namespace {

TEST(ConstraintKernels, Atan2MatchesTheLibraryOnEveryOctantAndTheAxes) {
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    double worst = 0.0;
    for (int i = 0; i < 200000; ++i) {
        const double scale = std::pow(10.0, 6.0 * uniform(random));
        const double y = uniform(random) * scale;
        const double x = uniform(random) * scale;
        const double expected = std::atan2(y, x);
        worst = std::max(
            worst, std::abs(detail::atan2(y, x) - expected) / std::max(std::abs(expected), 1e-300));
    }
    EXPECT_LT(worst, 4e-16);
    EXPECT_EQ(detail::atan2(0.0, 0.0), 0.0);
    EXPECT_EQ(detail::atan2(0.0, 1.0), 0.0);
    EXPECT_DOUBLE_EQ(detail::atan2(1.0, 0.0), std::numbers::pi / 2);
    EXPECT_DOUBLE_EQ(detail::atan2(-1.0, 0.0), -std::numbers::pi / 2);
    EXPECT_DOUBLE_EQ(detail::atan2(0.0, -1.0), std::numbers::pi);
    EXPECT_DOUBLE_EQ(detail::atan2(1.0, 1.0), std::numbers::pi / 4);
    EXPECT_DOUBLE_EQ(detail::atan2(-1.0, -1.0), -3.0 * std::numbers::pi / 4);
    // Tiny and huge ratios.
    EXPECT_DOUBLE_EQ(detail::atan2(1e-300, 1.0), 1e-300);
    EXPECT_DOUBLE_EQ(detail::atan2(1.0, 1e-300), std::numbers::pi / 2);
}

// A reference bending projection built on dihedral.hpp (std::atan2, normalized normals).
void reference_bending(std::vector<PackedVertex>& x, const std::int32_t (&v)[4], double rest,
                       double alpha) {
    const auto at = [&](int k) {
        const PackedVertex& p = x[static_cast<std::size_t>(v[k])];
        return Vec3d{p.x, p.y, p.z};
    };
    const DihedralAngle angle = dihedral_angle(at(0), at(1), at(2), at(3));
    if (!angle.is_valid) {
        return;
    }
    double weight = 0.0;
    for (int k = 0; k < 4; ++k) {
        weight += x[static_cast<std::size_t>(v[k])].inverse_mass *
                  squared_norm(angle.gradient[static_cast<std::size_t>(k)]);
    }
    double c = angle.angle - rest;
    c = c > std::numbers::pi ? c - 2.0 * std::numbers::pi : c;
    c = c <= -std::numbers::pi ? c + 2.0 * std::numbers::pi : c;
    const double lambda = -c / (weight + alpha);
    for (int k = 0; k < 4; ++k) {
        PackedVertex& p = x[static_cast<std::size_t>(v[k])];
        const Vec3d g = angle.gradient[static_cast<std::size_t>(k)] * (p.inverse_mass * lambda);
        p.x += g.x;
        p.y += g.y;
        p.z += g.z;
    }
}

// n independent hinges (4 vertices each, disjoint), randomly folded, some pinned vertices and
// some degenerate hinges.
struct Hinges {
    std::vector<PackedVertex> x;
    std::vector<std::int32_t> v0, v1, v2, v3;
    std::vector<double> rest;
};

Hinges random_hinges(int n, std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Hinges h;
    for (int i = 0; i < n; ++i) {
        const double fold = 3.0 * uniform(random);
        const double s = 0.01 * (1.5 + uniform(random));
        // Shared edge along x; wings at angle ±fold/2 about it, jittered.
        const PackedVertex v2{0.0, 0.0, 0.0, 1.0 + uniform(random)};
        const PackedVertex v3{s, 0.0, 0.0, 1.0 + uniform(random)};
        const double half = 0.5 * fold;
        PackedVertex v0{0.5 * s, s * std::cos(half), s * std::sin(half), 2.0};
        PackedVertex v1{0.5 * s, -s * std::cos(half), s * std::sin(half), 0.5};
        v0.x += 0.1 * s * uniform(random);
        v1.z += 0.1 * s * uniform(random);
        if (i % 7 == 3) {
            v0.inverse_mass = 0.0;  // pinned
        }
        if (i % 11 == 5) {
            v1 = v2;  // degenerate wing: skipped
        }
        if (i % 13 == 6) {
            v0.inverse_mass = v1.inverse_mass = 0.0;
            h.x.push_back(v0);
            h.x.push_back(v1);
            h.x.push_back({v2.x, v2.y, v2.z, 0.0});
            h.x.push_back({v3.x, v3.y, v3.z, 0.0});  // all pinned: skipped
        } else {
            h.x.push_back(v0);
            h.x.push_back(v1);
            h.x.push_back(v2);
            h.x.push_back(v3);
        }
        // Vertices in shuffled slots so that lanes gather from scattered rows.
        const auto base = static_cast<std::int32_t>(4 * i);
        h.v0.push_back(base);
        h.v1.push_back(base + 1);
        h.v2.push_back(base + 2);
        h.v3.push_back(base + 3);
        h.rest.push_back(0.3 * uniform(random));
    }
    return h;
}

TEST(ConstraintKernels, BendingMatchesTheDihedralReference) {
    Hinges h = random_hinges(257, 1);
    const std::vector<PackedVertex> initial = h.x;
    std::vector<PackedVertex> expected = h.x;
    const double alpha = 1e-3;
    const BendingColumns columns{h.v0.data(), h.v1.data(), h.v2.data(), h.v3.data(), h.rest.data()};
    project_bending(h.x.data(), columns, 0, static_cast<std::int64_t>(h.rest.size()), alpha);
    for (std::size_t k = 0; k < h.rest.size(); ++k) {
        const std::int32_t v[4] = {h.v0[k], h.v1[k], h.v2[k], h.v3[k]};
        reference_bending(expected, v, h.rest[k], alpha);
    }
    int moved = 0;
    for (std::size_t i = 0; i < h.x.size(); ++i) {
        EXPECT_NEAR(h.x[i].x, expected[i].x, 1e-13) << i;
        EXPECT_NEAR(h.x[i].y, expected[i].y, 1e-13) << i;
        EXPECT_NEAR(h.x[i].z, expected[i].z, 1e-13) << i;
        moved += expected[i].z != initial[i].z ? 1 : 0;
    }
    EXPECT_GT(moved, 500);  // the projections did something
}

TEST(ConstraintKernels, BendingReducesTheAngleErrorOfAStiffHinge) {
    // One rigid projection of a linearized constraint: the error shrinks to second order.
    Hinges h = random_hinges(1, 3);
    h.x[0].inverse_mass = h.x[1].inverse_mass = h.x[2].inverse_mass = h.x[3].inverse_mass = 1.0;
    const auto angle = [&] {
        const auto at = [&](int k) {
            return Vec3d{h.x[static_cast<std::size_t>(k)].x, h.x[static_cast<std::size_t>(k)].y,
                         h.x[static_cast<std::size_t>(k)].z};
        };
        return dihedral_angle_value(at(0), at(1), at(2), at(3));
    };
    h.rest[0] = angle() + 0.05;
    const BendingColumns columns{h.v0.data(), h.v1.data(), h.v2.data(), h.v3.data(), h.rest.data()};
    project_bending(h.x.data(), columns, 0, 1, 0.0);
    EXPECT_LT(std::abs(angle() - h.rest[0]), 0.05 * 0.05);
}

TEST(ConstraintKernels, StretchMeetsTheRestLengthAndConservesTheCentreOfMass) {
    std::vector<PackedVertex> x{{0.0, 0.0, 0.0, 1.0}, {1.0, 2.0, 2.0, 3.0}};
    const std::int32_t p = 0;
    const std::int32_t q = 1;
    const double rest = 2.0;
    const StretchColumns columns{&p, &q, &rest};
    const auto centre = [&] {
        // Weighted by mass = 1 / inverse mass.
        return Vec3d{x[0].x / 1.0 + x[1].x / 3.0, x[0].y / 1.0 + x[1].y / 3.0,
                     x[0].z / 1.0 + x[1].z / 3.0};
    };
    const Vec3d before = centre();
    project_stretch(x.data(), columns, 0, 1, 0.0);
    EXPECT_NEAR(std::hypot(x[1].x - x[0].x, x[1].y - x[0].y, x[1].z - x[0].z), 2.0, 1e-15);
    EXPECT_NEAR(centre().x, before.x, 1e-15);
    EXPECT_NEAR(centre().y, before.y, 1e-15);
    EXPECT_NEAR(centre().z, before.z, 1e-15);
}

TEST(ConstraintKernels, VectorAndScalarKernelsGiveTheSameBits) {
    if (!has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this CPU";
    }
    // Bending: every remainder of a range split (the vector kernel takes groups of four).
    for (const std::int64_t end : {0, 1, 3, 4, 5, 8, 130, 257}) {
        Hinges vector = random_hinges(257, 11);
        Hinges scalar = vector;
        const double alpha = 2.0;
        const BendingColumns cv{vector.v0.data(), vector.v1.data(), vector.v2.data(),
                                vector.v3.data(), vector.rest.data()};
        const BendingColumns cs{scalar.v0.data(), scalar.v1.data(), scalar.v2.data(),
                                scalar.v3.data(), scalar.rest.data()};
        project_bending(vector.x.data(), cv, 0, end, alpha);
        allow_avx2(false);
        project_bending(scalar.x.data(), cs, 0, end, alpha);
        allow_avx2(true);
        for (std::size_t i = 0; i < vector.x.size(); ++i) {
            ASSERT_EQ(vector.x[i].x, scalar.x[i].x) << end << " " << i;
            ASSERT_EQ(vector.x[i].y, scalar.x[i].y) << end << " " << i;
            ASSERT_EQ(vector.x[i].z, scalar.x[i].z) << end << " " << i;
        }
    }
    // Stretch: random edges over disjoint vertex pairs, a pinned pair and a zero-length edge.
    std::mt19937_64 random(5);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    std::vector<PackedVertex> x;
    std::vector<std::int32_t> p;
    std::vector<std::int32_t> q;
    std::vector<double> rest;
    for (int i = 0; i < 103; ++i) {
        const PackedVertex a{uniform(random), uniform(random), uniform(random),
                             i == 9 ? 0.0 : 1.0 + uniform(random)};
        PackedVertex b{uniform(random), uniform(random), uniform(random),
                       i == 9 ? 0.0 : 1.0 + uniform(random)};
        if (i == 17) {
            b = {a.x, a.y, a.z, 1.0};
        }
        x.push_back(a);
        x.push_back(b);
        // Pairs in scrambled order: lanes read rows far apart.
        p.push_back(2 * ((i * 37) % 103));
        q.push_back(2 * ((i * 37) % 103) + 1);
        rest.push_back(0.5 + 0.25 * uniform(random));
    }
    std::vector<PackedVertex> y = x;
    const StretchColumns columns{p.data(), q.data(), rest.data()};
    project_stretch(x.data(), columns, 0, 103, 1e-4);
    allow_avx2(false);
    project_stretch(y.data(), columns, 0, 103, 1e-4);
    allow_avx2(true);
    for (std::size_t i = 0; i < x.size(); ++i) {
        ASSERT_EQ(x[i].x, y[i].x) << i;
        ASSERT_EQ(x[i].y, y[i].y) << i;
        ASSERT_EQ(x[i].z, y[i].z) << i;
    }
}

}  // namespace
}  // namespace pliant::cloth::detail
