#include "pliant/geometry/exact_predicates.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <random>
#include <vector>

namespace pliant::geometry {
namespace {

__extension__ typedef unsigned __int128 Uint128;

// Independent reference: signed big integers (base 2^32 magnitude). Every double is an integer
// multiple of 2^-1074, so the inputs times a common power of two are integers, and the
// determinant of the scaled coordinates — same sign — is computed exactly without any
// floating-point arithmetic.
struct BigInt {
    bool negative = false;
    std::vector<std::uint32_t> limbs;  // little endian, no leading zero limbs; empty = 0

    int sign() const { return limbs.empty() ? 0 : (negative ? -1 : 1); }
};

void trim(BigInt& a) {
    while (!a.limbs.empty() && a.limbs.back() == 0) {
        a.limbs.pop_back();
    }
    if (a.limbs.empty()) {
        a.negative = false;
    }
}

int compare_magnitude(const BigInt& a, const BigInt& b) {
    if (a.limbs.size() != b.limbs.size()) {
        return a.limbs.size() < b.limbs.size() ? -1 : 1;
    }
    for (std::size_t i = a.limbs.size(); i-- > 0;) {
        if (a.limbs[i] != b.limbs[i]) {
            return a.limbs[i] < b.limbs[i] ? -1 : 1;
        }
    }
    return 0;
}

// |a| + |b|, or |a| - |b| for |a| ≥ |b|.
std::vector<std::uint32_t> add_magnitudes(const BigInt& a, const BigInt& b) {
    std::vector<std::uint32_t> out(std::max(a.limbs.size(), b.limbs.size()) + 1, 0);
    std::uint64_t carry = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
        const std::uint64_t s =
            carry + (i < a.limbs.size() ? a.limbs[i] : 0) + (i < b.limbs.size() ? b.limbs[i] : 0);
        out[i] = static_cast<std::uint32_t>(s);
        carry = s >> 32;
    }
    return out;
}

std::vector<std::uint32_t> subtract_magnitudes(const BigInt& a, const BigInt& b) {
    std::vector<std::uint32_t> out(a.limbs.size(), 0);
    std::int64_t borrow = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
        std::int64_t d = static_cast<std::int64_t>(a.limbs[i]) - borrow -
                         static_cast<std::int64_t>(i < b.limbs.size() ? b.limbs[i] : 0);
        borrow = d < 0 ? 1 : 0;
        out[i] = static_cast<std::uint32_t>(d + (borrow << 32));
    }
    return out;
}

BigInt operator+(const BigInt& a, const BigInt& b) {
    BigInt out;
    if (a.negative == b.negative) {
        out.limbs = add_magnitudes(a, b);
        out.negative = a.negative;
    } else if (compare_magnitude(a, b) >= 0) {
        out.limbs = subtract_magnitudes(a, b);
        out.negative = a.negative;
    } else {
        out.limbs = subtract_magnitudes(b, a);
        out.negative = b.negative;
    }
    trim(out);
    return out;
}

BigInt operator-(BigInt a) {
    a.negative = !a.negative;
    trim(a);
    return a;
}

BigInt operator-(const BigInt& a, const BigInt& b) {
    return a + (-b);
}

BigInt operator*(const BigInt& a, const BigInt& b) {
    BigInt out;
    out.limbs.assign(a.limbs.size() + b.limbs.size(), 0);
    for (std::size_t i = 0; i < a.limbs.size(); ++i) {
        std::uint64_t carry = 0;
        for (std::size_t j = 0; j < b.limbs.size(); ++j) {
            const std::uint64_t t =
                static_cast<std::uint64_t>(a.limbs[i]) * b.limbs[j] + out.limbs[i + j] + carry;
            out.limbs[i + j] = static_cast<std::uint32_t>(t);
            carry = t >> 32;
        }
        out.limbs[i + b.limbs.size()] = static_cast<std::uint32_t>(carry);
    }
    out.negative = a.negative != b.negative;
    trim(out);
    return out;
}

// The smallest k such that x · 2^k is an integer (x ≠ 0); every double has k ≤ 1074.
int integer_shift(double x) {
    int exponent = 0;
    const double fraction = std::frexp(std::fabs(x), &exponent);  // x = fraction · 2^exponent
    auto mantissa = static_cast<std::uint64_t>(std::ldexp(fraction, 53));
    return 53 - exponent - std::countr_zero(mantissa);
}

// The common shift of a set of coordinates: each x · 2^shift is an integer.
int common_shift(std::initializer_list<double> values) {
    int shift = -1100;
    for (const double x : values) {
        if (x != 0.0) {
            shift = std::max(shift, integer_shift(x));
        }
    }
    return shift;
}

// x · 2^shift as an exact integer (requires integer_shift(x) ≤ shift).
BigInt scaled_integer(double x, int shift) {
    BigInt out;
    if (x == 0.0) {
        return out;
    }
    int exponent = 0;
    const double fraction = std::frexp(std::fabs(x), &exponent);
    auto mantissa = static_cast<std::uint64_t>(std::ldexp(fraction, 53));
    int bits = exponent - 53 + shift;  // x · 2^shift = mantissa · 2^bits
    while (bits < 0) {
        EXPECT_EQ(mantissa & 1u, 0u);
        mantissa >>= 1;
        ++bits;
    }
    const auto limb = static_cast<std::size_t>(bits / 32);
    const Uint128 shifted = static_cast<Uint128>(mantissa) << (bits % 32);
    out.limbs.assign(limb + 3, 0);
    out.limbs[limb] = static_cast<std::uint32_t>(shifted);
    out.limbs[limb + 1] = static_cast<std::uint32_t>(shifted >> 32);
    out.limbs[limb + 2] = static_cast<std::uint32_t>(shifted >> 64);
    out.negative = x < 0;
    trim(out);
    return out;
}

// Determinants of the coordinates scaled by a common power of two: the same sign.
int reference_orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    const int shift = common_shift({a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z, d.x, d.y, d.z});
    BigInt u[3];
    BigInt v[3];
    BigInt w[3];
    for (int k = 0; k < 3; ++k) {
        const BigInt ak = scaled_integer(a[k], shift);
        u[k] = scaled_integer(b[k], shift) - ak;
        v[k] = scaled_integer(c[k], shift) - ak;
        w[k] = scaled_integer(d[k], shift) - ak;
    }
    const BigInt det = w[0] * (u[1] * v[2] - u[2] * v[1]) + w[1] * (u[2] * v[0] - u[0] * v[2]) +
                       w[2] * (u[0] * v[1] - u[1] * v[0]);
    return det.sign();
}

int reference_orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const int shift = common_shift({ax, ay, bx, by, cx, cy});
    const BigInt sax = scaled_integer(ax, shift);
    const BigInt say = scaled_integer(ay, shift);
    const BigInt det = (scaled_integer(bx, shift) - sax) * (scaled_integer(cy, shift) - say) -
                       (scaled_integer(by, shift) - say) * (scaled_integer(cx, shift) - sax);
    return det.sign();
}

int sign_of(double x) {
    return x > 0 ? 1 : (x < 0 ? -1 : 0);
}

int naive_orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    return sign_of(dot(cross(b - a, c - a), d - a));
}

int naive_orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    return sign_of((bx - ax) * (cy - ay) - (by - ay) * (cx - ax));
}

TEST(ExactPredicates, ReferenceArithmetic) {
    EXPECT_EQ((scaled_integer(3.0, 0) * scaled_integer(-2.0, 0) +
               scaled_integer(6.0, 0) * scaled_integer(1.0, 0))
                  .sign(),
              0);
    EXPECT_EQ(integer_shift(0x1p-1074), 1074);
    EXPECT_EQ(integer_shift(3.0 * 0x1p40), -40);
    EXPECT_EQ((scaled_integer(0x1p-1074, 1074) - scaled_integer(0.0, 1074)).sign(), 1);
    EXPECT_EQ((scaled_integer(1.0, 52) - scaled_integer(1.0 + 0x1p-52, 52)).sign(), -1);
    EXPECT_EQ((scaled_integer(0x1p100, 0) - scaled_integer(0x1p100 - 0x1p47, 0)).sign(), 1);
    EXPECT_EQ(reference_orient2d(0, 0, 1, 0, 0, 1), 1);
    EXPECT_EQ(reference_orient3d({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0x1p-1074}), 1);
}

TEST(ExactPredicates, Orient3dSignConvention) {
    const Vec3d a{0, 0, 0};
    const Vec3d b{1, 0, 0};
    const Vec3d c{0, 1, 0};
    // (b - a) × (c - a) = +z: positive on the +z side.
    EXPECT_EQ(orient3d(a, b, c, {0.2, 0.3, 1.0}), 1);
    EXPECT_EQ(orient3d(a, b, c, {0.2, 0.3, -1.0}), -1);
    EXPECT_EQ(orient3d(a, b, c, {5.0, -7.0, 0.0}), 0);
    EXPECT_EQ(orient3d(a, a, c, {0.0, 0.0, 1.0}), 0);  // repeated point
    // Odd permutations flip the sign, even ones keep it.
    const Vec3d d{0.1, 0.7, 0.25};
    EXPECT_EQ(orient3d(b, a, c, d), -1);
    EXPECT_EQ(orient3d(b, c, a, d), 1);
    EXPECT_EQ(orient3d(a, b, d, c), -1);
}

TEST(ExactPredicates, Orient2dSignConvention) {
    EXPECT_EQ(orient2d(0, 0, 1, 0, 0, 1), 1);   // counter-clockwise
    EXPECT_EQ(orient2d(0, 0, 0, 1, 1, 0), -1);  // clockwise
    EXPECT_EQ(orient2d(0, 0, 1, 1, 3, 3), 0);   // collinear
    EXPECT_EQ(orient2d(2, 2, 2, 2, 3, -1), 0);  // repeated point
    EXPECT_EQ(orient2d(1, 0, 0, 1, 0, 0), 1);   // cyclic shift keeps the sign
}

// Shewchuk's example: a point a few ulps from the line through (12, 12) and (24, 24). Plain
// double arithmetic gets many of these signs wrong; the predicate must get all of them right.
TEST(ExactPredicates, Orient2dNearlyCollinearGrid) {
    int naive_wrong = 0;
    for (int i = 0; i < 64; ++i) {
        for (int j = 0; j < 64; ++j) {
            const double ax = 0.5 + i * 0x1p-53;
            const double ay = 0.5 + j * 0x1p-53;
            const int expected = reference_orient2d(ax, ay, 12, 12, 24, 24);
            ASSERT_EQ(orient2d(ax, ay, 12, 12, 24, 24), expected) << i << ", " << j;
            ASSERT_EQ(orient2d(12, 12, 24, 24, ax, ay), expected) << i << ", " << j;
            naive_wrong += naive_orient2d(ax, ay, 12, 12, 24, 24) != expected ? 1 : 0;
        }
    }
    EXPECT_GT(naive_wrong, 100) << "the grid no longer defeats plain double arithmetic";
}

// The 3D analogue: b, c, d on the plane x = y, a a few ulps off it.
TEST(ExactPredicates, Orient3dNearlyCoplanarGrid) {
    const Vec3d b{12, 12, 0.75};
    const Vec3d c{24, 24, -7};
    const Vec3d d{3, 3, 5};
    int naive_wrong = 0;
    for (int i = 0; i < 64; ++i) {
        for (int j = 0; j < 64; ++j) {
            const Vec3d a{0.5 + i * 0x1p-53, 0.5 + j * 0x1p-53, 0.5};
            const int expected = reference_orient3d(a, b, c, d);
            ASSERT_EQ(orient3d(a, b, c, d), expected) << i << ", " << j;
            ASSERT_EQ(orient3d(d, c, b, a), expected) << i << ", " << j;  // two swaps
            naive_wrong += naive_orient3d(a, b, c, d) != expected ? 1 : 0;
        }
    }
    EXPECT_GT(naive_wrong, 100) << "the grid no longer defeats plain double arithmetic";
}

// Exactly coplanar points (an integer lattice plane, scaled by a power of two) after large
// dyadic translations: the answer is exactly 0, and ±1 after moving one point by one unit of the
// lattice's last place.
TEST(ExactPredicates, Orient3dCoplanarAfterLargeTranslation) {
    std::mt19937_64 rng(11);
    std::uniform_int_distribution<std::int64_t> small(-(1 << 12), 1 << 12);
    std::uniform_int_distribution<std::int64_t> coefficient(-(1 << 10), 1 << 10);
    const double unit = 0x1p-24;
    for (const double offset : {0.0, 0x1p20, -0x1p25, 0x1.8p27}) {
        for (int trial = 0; trial < 400; ++trial) {
            const Vec3d u{double(coefficient(rng)), double(coefficient(rng)),
                          double(coefficient(rng))};
            const Vec3d v{double(coefficient(rng)), double(coefficient(rng)),
                          double(coefficient(rng))};
            const auto point = [&] {
                const auto i = double(small(rng));
                const auto j = double(small(rng));
                return (u * i + v * j) * unit + Vec3d{offset, -offset, 0.5 * offset};
            };
            const Vec3d a = point();
            const Vec3d b = point();
            const Vec3d c = point();
            Vec3d d = point();
            ASSERT_EQ(reference_orient3d(a, b, c, d), 0);
            ASSERT_EQ(orient3d(a, b, c, d), 0) << "offset " << offset << " trial " << trial;
            const int axis = trial % 3;
            d[axis] += (trial % 2 == 0 ? 1.0 : -1.0) * std::max(unit, std::fabs(offset) * 0x1p-52);
            ASSERT_EQ(orient3d(a, b, c, d), reference_orient3d(a, b, c, d))
                << "offset " << offset << " trial " << trial;
        }
    }
}

// Points that share a coordinate (a flat sheet in an axis plane, points along a grid's rows),
// which the predicates decide without the exact path, and the same with one point moved off by
// one ulp, against the reference, at scales across the documented domain.
TEST(ExactPredicates, PointsSharingACoordinateAgainstReference) {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (const double scale : {1.0, 1e-6, 0x1p-280, 0x1p+290}) {
        for (int trial = 0; trial < 600; ++trial) {
            const auto random_point = [&] {
                return Vec3d{unit(rng), unit(rng), unit(rng)} * scale;
            };
            Vec3d p[4] = {random_point(), random_point(), random_point(), random_point()};
            const int axis = trial % 3;
            const double shared = p[0][axis];
            for (Vec3d& q : p) {
                q[axis] = shared;
            }
            ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), 0) << scale << " " << trial;
            const int other = (axis + 1) % 3;
            ASSERT_EQ(
                orient2d(p[0][axis], p[0][other], p[1][axis], p[1][other], p[2][axis], p[2][other]),
                0);
            const int moved = trial % 4;
            p[moved][axis] = std::nextafter(shared, trial % 2 == 0 ? 1.0 : -1.0);
            ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), reference_orient3d(p[0], p[1], p[2], p[3]))
                << scale << " " << trial;
            ASSERT_NE(orient3d(p[0], p[1], p[2], p[3]), 0) << scale << " " << trial;
            ASSERT_EQ(
                orient2d(p[0][axis], p[0][other], p[1][axis], p[1][other], p[2][axis], p[2][other]),
                reference_orient2d(p[0][axis], p[0][other], p[1][axis], p[1][other], p[2][axis],
                                   p[2][other]));
        }
    }
}

// Random points, including nearly degenerate ones (a fourth point on the plane of three, then
// rounded), at scales across the documented domain.
TEST(ExactPredicates, RandomAgainstReference) {
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_real_distribution<double> weight(-2.0, 3.0);
    int naive_wrong = 0;
    for (const double scale : {1.0, 0x1p-250, 0x1p+250, 1e-6, 1e6}) {
        for (int trial = 0; trial < 2000; ++trial) {
            const auto random_point = [&] {
                return Vec3d{unit(rng), unit(rng), unit(rng)} * scale;
            };
            const Vec3d a = random_point();
            const Vec3d b = random_point();
            const Vec3d c = random_point();
            Vec3d d = random_point();
            if (trial % 2 == 1) {  // on the plane up to rounding
                d = a + (b - a) * weight(rng) + (c - a) * weight(rng);
            }
            const int expected = reference_orient3d(a, b, c, d);
            ASSERT_EQ(orient3d(a, b, c, d), expected) << "scale " << scale << " trial " << trial;
            ASSERT_EQ(orient3d(b, a, c, d), -expected);
            ASSERT_EQ(orient2d(a.x, a.y, b.x, b.y, d.x, d.y),
                      reference_orient2d(a.x, a.y, b.x, b.y, d.x, d.y));
            naive_wrong += naive_orient3d(a, b, c, d) != expected ? 1 : 0;
        }
    }
    EXPECT_GT(naive_wrong, 0) << "no case needed the exact path";
}

// Products near the ends of the domain: 2^-300 and 2^300 scale, tiny relative perturbations.
TEST(ExactPredicates, DomainEnds) {
    for (const double scale : {0x1p-299, 0x1p-290, 0x1p+295}) {
        const Vec3d b = Vec3d{12, 12, 0.75} * scale;
        const Vec3d c = Vec3d{24, 24, -7} * scale;
        const Vec3d d = Vec3d{3, 3, 5} * scale;
        for (int i = -3; i <= 3; ++i) {
            const Vec3d a = Vec3d{1 + i * 0x1p-52, 1, 0.5} * scale;  // |coordinates| ≥ 2^-300
            EXPECT_EQ(orient3d(a, b, c, d), reference_orient3d(a, b, c, d)) << scale << " " << i;
            EXPECT_EQ(orient3d(a, b, c, d),
                      orient3d(a * (1 / scale), b * (1 / scale), c * (1 / scale), d * (1 / scale)));
            EXPECT_EQ(orient2d(a.x, a.y, b.x, b.y, c.x, c.y),
                      reference_orient2d(a.x, a.y, b.x, b.y, c.x, c.y));
        }
    }
    EXPECT_TRUE(in_exact_domain(0.0));
    EXPECT_TRUE(in_exact_domain(-0x1p-300));
    EXPECT_TRUE(in_exact_domain(0x1p300));
    EXPECT_FALSE(in_exact_domain(0x1p-301));
    EXPECT_FALSE(in_exact_domain(1e300));
    EXPECT_FALSE(in_exact_domain(NAN));
    EXPECT_FALSE(in_exact_domain(-INFINITY));
}

}  // namespace
}  // namespace pliant::geometry
