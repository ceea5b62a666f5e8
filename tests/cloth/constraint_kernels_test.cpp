#include "pliant/cloth/detail/constraint_kernels.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "pliant/cloth/dihedral.hpp"
#include "pliant/cloth/stretch_chains.hpp"
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

// Success when a and b hold the same positions to the bit (== on every coordinate), else the
// first vertex that differs.
::testing::AssertionResult same_positions(const std::vector<PackedVertex>& a,
                                          const std::vector<PackedVertex>& b) {
    if (a.size() != b.size()) {
        return ::testing::AssertionFailure() << a.size() << " against " << b.size() << " vertices";
    }
    for (std::size_t i = 0; i < a.size(); ++i) {
        if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].z != b[i].z) {
            return ::testing::AssertionFailure()
                   << "vertex " << i << ": (" << a[i].x << ", " << a[i].y << ", " << a[i].z
                   << ") against (" << b[i].x << ", " << b[i].y << ", " << b[i].z << ")";
        }
    }
    return ::testing::AssertionSuccess();
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
        ASSERT_TRUE(same_positions(vector.x, scalar.x)) << "end " << end;
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
    EXPECT_TRUE(same_positions(x, y));
}

// Four chains side by side as a packet (lane l = chains[l]; an empty chain is a lane without a
// chain), over vertex records x (the last record: the padding vertex).
struct Packet {
    std::vector<std::int32_t> vertices;
    std::vector<double> rest;
    std::vector<std::int32_t> edges;  // lane l's edge k: index 64 l + k
    std::int32_t num_rows = 0;
    ChainPacket view() const { return {vertices.data(), rest.data(), edges.data(), num_rows}; }
};

Packet make_packet(const std::vector<std::vector<std::int32_t>>& chains,
                   const std::vector<std::vector<double>>& rests, std::int32_t padding) {
    Packet packet;
    for (const auto& chain : chains) {
        packet.num_rows = std::max(packet.num_rows, static_cast<std::int32_t>(chain.size()) - 1);
    }
    for (std::int32_t row = 0; row <= packet.num_rows; ++row) {
        for (std::size_t lane = 0; lane < 4; ++lane) {
            const auto& chain = chains[lane];
            const auto last = static_cast<std::int32_t>(chain.size()) - 1;
            packet.vertices.push_back(
                chain.empty() ? padding : chain[static_cast<std::size_t>(std::min(row, last))]);
            if (row < packet.num_rows) {
                packet.rest.push_back(row < last ? rests[lane][static_cast<std::size_t>(row)]
                                                 : -1.0);
                packet.edges.push_back(row < last ? 64 * static_cast<std::int32_t>(lane) + row
                                                  : -1);
            }
        }
    }
    return packet;
}

// The chain's linearized XPBD step by dense Gaussian elimination with partial pivoting: the
// matrix built entry by entry from J W Jᵀ (no tridiagonal structure assumed). Returns Δλ per
// edge (0 for edges that take no part).
std::vector<double> reference_chain(std::vector<PackedVertex>& x,
                                    const std::vector<std::int32_t>& chain,
                                    const std::vector<double>& rest, const ChainSolve& solve) {
    const std::size_t m = chain.size() - 1;
    std::vector<Vec3d> n(m, Vec3d{0.0, 0.0, 0.0});
    std::vector<double> c(m, 0.0);
    std::vector<bool> active(m, false);
    const auto at = [&](std::size_t k) -> PackedVertex& {
        return x[static_cast<std::size_t>(chain[k])];
    };
    for (std::size_t k = 0; k < m; ++k) {
        const Vec3d d{at(k + 1).x - at(k).x, at(k + 1).y - at(k).y, at(k + 1).z - at(k).z};
        const double length = norm(d);
        active[k] = at(k).inverse_mass + at(k + 1).inverse_mass > 0.0 && length > 0.0;
        if (active[k]) {
            n[k] = d * (1.0 / length);
            c[k] = length - rest[k];
        }
    }
    // Gradient of constraint k at chain vertex j.
    const auto gradient = [&](std::size_t k, std::size_t j) {
        if (!active[k]) {
            return Vec3d{0.0, 0.0, 0.0};
        }
        return j == k + 1 ? n[k] : j == k ? n[k] * -1.0 : Vec3d{0.0, 0.0, 0.0};
    };
    std::vector<std::vector<double>> a(m, std::vector<double>(m + 1, 0.0));
    for (std::size_t i = 0; i < m; ++i) {
        for (std::size_t k = 0; k < m; ++k) {
            for (std::size_t j = 0; j <= m; ++j) {
                a[i][k] += at(j).inverse_mass * dot(gradient(i, j), gradient(k, j));
            }
        }
        const double length = c[i] + rest[i];
        const double epsilon =
            solve.regularization +
            (active[i] ? solve.strain_regularization * std::abs(c[i]) / length : 0.0);
        a[i][i] = active[i] ? a[i][i] + epsilon * (at(i).inverse_mass + at(i + 1).inverse_mass) +
                                  solve.alpha
                            : 1.0;
        a[i][m] = -c[i];
    }
    for (std::size_t col = 0; col < m; ++col) {
        std::size_t pivot = col;
        for (std::size_t r = col + 1; r < m; ++r) {
            if (std::abs(a[r][col]) > std::abs(a[pivot][col])) {
                pivot = r;
            }
        }
        std::swap(a[col], a[pivot]);
        for (std::size_t r = 0; r < m; ++r) {
            if (r != col) {
                const double f = a[r][col] / a[col][col];
                for (std::size_t k = col; k <= m; ++k) {
                    a[r][k] -= f * a[col][k];
                }
            }
        }
    }
    std::vector<double> lambdas(m, 0.0);
    std::vector<Vec3d> step(m + 1, Vec3d{0.0, 0.0, 0.0});
    for (std::size_t k = 0; k < m; ++k) {
        lambdas[k] = a[k][m] / a[k][k];
        for (std::size_t j = 0; j <= m; ++j) {
            step[j] += gradient(k, j) * (at(j).inverse_mass * lambdas[k]);
        }
    }
    for (std::size_t j = 0; j <= m; ++j) {
        at(j).x += step[j].x;
        at(j).y += step[j].y;
        at(j).z += step[j].z;
    }
    return lambdas;
}

// Four random chains (9, 6, 2 edges and no chain) on their own vertices, randomly bent and
// stretched, with a zero-length edge and two fixed vertices inside the first, a fixed end of the
// second; the padding vertex last.
struct Chains {
    std::vector<PackedVertex> x;
    std::vector<std::vector<std::int32_t>> chains;
    std::vector<std::vector<double>> rests;
};

Chains random_chains(std::uint64_t seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    Chains c;
    for (const int length : {9, 6, 2, 0}) {
        std::vector<std::int32_t> chain;
        std::vector<double> rest;
        Vec3d p{uniform(random), uniform(random), uniform(random)};
        for (int k = 0; k <= length && length > 0; ++k) {
            chain.push_back(static_cast<std::int32_t>(c.x.size()));
            c.x.push_back({p.x, p.y, p.z, 1.0 + 0.5 * uniform(random)});
            p +=
                Vec3d{0.1 + 0.02 * uniform(random), 0.03 * uniform(random), 0.03 * uniform(random)};
            if (k < length) {
                rest.push_back(0.09 + 0.01 * uniform(random));
            }
        }
        c.chains.push_back(chain);
        c.rests.push_back(rest);
    }
    c.x[2].inverse_mass = 0.0;                                         // inside chain 0
    c.x[5].inverse_mass = 0.0;                                         // inside chain 0
    c.x[static_cast<std::size_t>(c.chains[1][0])].inverse_mass = 0.0;  // chain 1's first
    c.x[7] = {c.x[6].x, c.x[6].y, c.x[6].z, 1.0};  // chain 0: edge 6 of zero length
    c.x.push_back({0.0, 0.0, 0.0, 0.0});           // the padding vertex
    return c;
}

TEST(ConstraintKernels, ChainPacketSolvesTheLinearizedChainSystem) {
    for (const double regularization : {0.0, 0.01, 1.0}) {
        for (const double alpha : {0.0, 0.5}) {
            const ChainSolve solve{alpha, regularization, regularization > 0.0 ? 1.0 : 0.0};
            Chains chains = random_chains(21);
            const Packet packet = make_packet(chains.chains, chains.rests,
                                              static_cast<std::int32_t>(chains.x.size()) - 1);
            std::vector<PackedVertex> expected = chains.x;
            std::vector<double> expected_lambda(256, -7.0);
            for (std::size_t l = 0; l < 3; ++l) {
                const std::vector<double> lambdas =
                    reference_chain(expected, chains.chains[l], chains.rests[l], solve);
                for (std::size_t k = 0; k < lambdas.size(); ++k) {
                    expected_lambda[64 * l + k] = lambdas[k];
                }
            }
            std::vector<double> scratch(
                static_cast<std::size_t>(CHAIN_SCRATCH_PER_ROW * packet.num_rows));
            std::vector<double> lambda(256, -7.0);  // -7: not written
            project_chain_packet(chains.x.data(), packet.view(), solve, lambda.data(),
                                 scratch.data());
            for (std::size_t i = 0; i < chains.x.size(); ++i) {
                EXPECT_NEAR(chains.x[i].x, expected[i].x, 1e-12) << i;
                EXPECT_NEAR(chains.x[i].y, expected[i].y, 1e-12) << i;
                EXPECT_NEAR(chains.x[i].z, expected[i].z, 1e-12) << i;
            }
            for (std::size_t i = 0; i < lambda.size(); ++i) {
                EXPECT_NEAR(lambda[i], expected_lambda[i], 1e-12) << i;
            }
            EXPECT_EQ(chains.x.back().x, 0.0);                   // the padding vertex stays
            EXPECT_EQ(chains.x[2].x, random_chains(21).x[2].x);  // fixed
            EXPECT_EQ(chains.x[5].x, random_chains(21).x[5].x);
        }
    }
}

TEST(ConstraintKernels, AStraightChainUnderLoadComesToItsRestLengthInOneSolve) {
    // A vertical chain of 50 edges hanging from a pinned top, every vertex displaced down by
    // gravity's step: a single-edge sweep fixes only the top edge's share; the chain solve
    // restores every length at once (the linearization is exact along a straight chain).
    std::vector<PackedVertex> x;
    std::vector<std::int32_t> chain;
    std::vector<double> rest;
    for (int k = 0; k <= 50; ++k) {
        const double sag = k == 0 ? 0.0 : 1e-4 * k;  // stretched, more towards the bottom
        x.push_back({0.0, 0.0, -0.02 * k - sag, k == 0 ? 0.0 : 100.0});
        chain.push_back(k);
        if (k < 50) {
            rest.push_back(0.02);
        }
    }
    x.push_back({0.0, 0.0, 0.0, 0.0});
    const Packet packet = make_packet({chain, {}, {}, {}}, {rest, {}, {}, {}}, 51);
    std::vector<double> scratch(static_cast<std::size_t>(CHAIN_SCRATCH_PER_ROW * packet.num_rows));
    std::vector<double> lambda(64, 0.0);
    project_chain_packet(x.data(), packet.view(), {0.0, 0.0}, lambda.data(), scratch.data());
    for (int k = 0; k < 50; ++k) {
        EXPECT_NEAR(x[static_cast<std::size_t>(k)].z - x[static_cast<std::size_t>(k) + 1].z, 0.02,
                    1e-15);
    }
}

TEST(ConstraintKernels, ATautChainBetweenFixedEndsIsNotKickedSideways) {
    // 20 edges of 5 cm between two fixed vertices, stretched by 10 % with a zigzag of ±0.1 mm:
    // the stretch cannot go (its ends are fixed), and a uniform tension along the chain changes
    // no length to first order. With ε = 0.01 alone one solve grows the zigzag to 1.8 mm; with
    // the solver's damping (ε, and κ on the 10 % strain) not beyond its 0.1 mm.
    const int m = 20;
    std::vector<PackedVertex> x;
    std::vector<std::int32_t> chain;
    std::vector<double> rest(m, 0.05);
    for (int k = 0; k <= m; ++k) {
        const double z = (k % 2 == 0 ? 1e-4 : -1e-4) * (k > 0 && k < m ? 1.0 : 0.0);
        x.push_back({0.055 * k, 0.0, z, k == 0 || k == m ? 0.0 : 1.0 / 3e-4});
        chain.push_back(k);
    }
    x.push_back({0.0, 0.0, 0.0, 0.0});
    const Packet packet = make_packet({chain, {}, {}, {}}, {rest, {}, {}, {}}, m + 1);
    std::vector<double> scratch(static_cast<std::size_t>(CHAIN_SCRATCH_PER_ROW * packet.num_rows));
    std::vector<double> lambda(64, 0.0);
    const double alpha = 1e-7 * 960.0 * 960.0;  // the default compliance at 40 substeps, 24 fps
    const auto zigzag_after = [&](double regularization, double strain_regularization) {
        std::vector<PackedVertex> y = x;
        project_chain_packet(y.data(), packet.view(),
                             {alpha, regularization, strain_regularization}, lambda.data(),
                             scratch.data());
        double largest = 0.0;
        for (int k = 0; k <= m; ++k) {
            largest = std::max(largest, std::abs(y[static_cast<std::size_t>(k)].z));
        }
        return largest;
    };
    EXPECT_GT(zigzag_after(0.01, 0.0), 1e-3);
    EXPECT_LT(zigzag_after(CHAIN_REGULARIZATION, CHAIN_STRAIN_REGULARIZATION), 1.1e-4);
}

TEST(ConstraintKernels, ChainVectorAndScalarKernelsGiveTheSameBits) {
    if (!has_avx2()) {
        GTEST_SKIP() << "no AVX2 on this CPU";
    }
    for (const std::uint64_t seed : {1, 2, 3, 4}) {
        Chains vector = random_chains(seed);
        Chains scalar = vector;
        const Packet packet = make_packet(vector.chains, vector.rests,
                                          static_cast<std::int32_t>(vector.x.size()) - 1);
        std::vector<double> scratch(
            static_cast<std::size_t>(CHAIN_SCRATCH_PER_ROW * packet.num_rows));
        std::vector<double> vector_lambda(256, 0.0);
        std::vector<double> scalar_lambda(256, 0.0);
        const ChainSolve solve{1e-3, 0.01, 1.0};
        project_chain_packet(vector.x.data(), packet.view(), solve, vector_lambda.data(),
                             scratch.data());
        allow_avx2(false);
        project_chain_packet(scalar.x.data(), packet.view(), solve, scalar_lambda.data(),
                             scratch.data());
        allow_avx2(true);
        ASSERT_TRUE(same_positions(vector.x, scalar.x)) << "seed " << seed;
        EXPECT_EQ(vector_lambda, scalar_lambda);
    }
}
}  // namespace
}  // namespace pliant::cloth::detail
