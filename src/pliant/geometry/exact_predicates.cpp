#include "pliant/geometry/exact_predicates.hpp"

#include <array>
#include <cfloat>
#include <cmath>
#include <limits>

// The error-free transformations below are exact only if every + - * is rounded once, to nearest,
// in binary64: no fast-math reassociation, no x87 extended precision, no contraction of a * b + c
// into an fma (pliant compiles everything with -ffp-contract=off, cmake/PliantCodegen.cmake; GCC's
// default for C++ is "fast"). The only fma here is two_product's explicit std::fma; the
// instructions GCC 12 generates for this file under -march=native contain no other.
#if defined(__FAST_MATH__)
#error "exact_predicates.cpp must not be compiled with -ffast-math"
#endif
#if FLT_EVAL_METHOD != 0
#error "exact_predicates.cpp needs FLT_EVAL_METHOD == 0 (no extended-precision intermediates)"
#endif
static_assert(std::numeric_limits<double>::is_iec559 && std::numeric_limits<double>::digits == 53);

namespace pliant::geometry {
namespace {

// ---------------------------------------------------------------------------------------------
// Why the filters are rigorous.
//
// Standard model (Higham, "Accuracy and Stability of Numerical Algorithms", §2.2): a rounded
// operation returns (x op y)(1 + δ), |δ| ≤ u = 2^-53, when its result is normal; a sum or
// difference whose result is subnormal is exact; a product that underflows returns
// xy(1 + δ) + η with |η| ≤ 2^-1075.
//
// orient3d: F = fl(fl(wx cx + wy cy) + wz cz) with c = u × v, u = b - a, v = c - a, w = d - a,
// each difference, product and sum rounded. Each of the six monomials of the exact determinant E
// (e.g. wx uy vz) reaches F multiplied by at most 8 factors (1 + δ): three differences, the
// product in the cross product, its subtraction, the product with w, two sums. So
// |F - E| ≤ γ8 · P with γ8 = 8u / (1 - 8u) and P the sum of the monomials' magnitudes. The code
// evaluates the same expression on absolute values, P~ (also ≤ 8 roundings per monomial, all
// terms ≥ 0), so P ≤ P~ / (1 - u)^8. Underflow: inside the domain (header) every nonzero
// difference is ≥ 2^-352, a product of two is ≥ 2^-704 (normal), and only the three final
// products can underflow, adding at most 3 · 2^-1075 (1 + u)^2 < 2^-1073 to F and to P~. With
// P~ ≥ FILTER_MIN = 2^-900 that is below 2^-173 P~, so
//     |F - E| ≤ (γ8 (1 - u)^-8 (1 + 2^-173) + 2^-173) P~ < 8.001 u P~ < fl(9u · P~),
// since 9u is a double and fl(9u P~) ≥ 9u P~ (1 - u) (normal: P~ ≥ 2^-900). Hence |F| > fl(9u P~)
// implies sign F = sign E. When P~ < FILTER_MIN, or |F| is within the bound, the exact path
// decides. (Shewchuk's tighter bound is (7 + 56u) u P~; 9u is simpler to prove and costs only a
// few more exact evaluations.)
//
// orient2d: F = fl(fl(ux vy) - fl(uy vx)): at most 4 roundings per monomial (two differences, a
// product, the subtraction), no underflow in the domain (products ≥ 2^-704), so
// |F - E| ≤ γ4 (1 - u)^-4 P~ < 4.001 u P~ < fl(5u · P~).
// ---------------------------------------------------------------------------------------------
constexpr double U = 0x1p-53;
constexpr double ORIENT3D_BOUND = 9.0 * U;
constexpr double ORIENT2D_BOUND = 5.0 * U;
constexpr double FILTER_MIN = 0x1p-900;

// ---------------------------------------------------------------------------------------------
// Expansion arithmetic (Shewchuk 1997, §2). An expansion is an unevaluated sum of doubles, its
// components stored in order of increasing magnitude, nonoverlapping, without zeros (the empty
// expansion is 0). Its sign is the sign of its last (largest) component, because nonoverlapping
// components satisfy |h_last| > |h_0 + … + h_last-1|.
//
// Why the exact path is exact in the domain: every coordinate is an integer multiple of 2^-352
// (a double with |x| ≥ 2^-300 has ulp ≥ 2^-352). Both outputs of two_sum / two_diff of multiples
// of q are multiples of q, and both outputs of two_product of multiples of q1 and q2 are
// multiples of q1 q2; the determinant's products are degree ≤ 3 in the differences, so every
// component is a multiple of 2^-1056 ≥ 2^-1074: the error term of each product is representable
// (possibly subnormal) and std::fma returns it exactly, and two_sum is exact for any doubles.
// Magnitudes stay below 2^910 (differences ≤ 2^301), far from overflow.
// ---------------------------------------------------------------------------------------------

// x + y = a + b exactly, x = fl(a + b) (Knuth's two-sum; no precondition on |a|, |b|).
inline void two_sum(double a, double b, double& x, double& y) {
    x = a + b;
    const double b_virtual = x - a;
    const double a_virtual = x - b_virtual;
    y = (a - a_virtual) + (b - b_virtual);
}

// x + y = a - b exactly, x = fl(a - b).
inline void two_diff(double a, double b, double& x, double& y) {
    x = a - b;
    const double b_virtual = a - x;
    const double a_virtual = x + b_virtual;
    y = (a - a_virtual) + (b_virtual - b);
}

// x + y = a · b exactly, x = fl(a · b): the fused multiply-add rounds a · b - x once, and that
// value is a double (see above), so it is exact.
inline void two_product(double a, double b, double& x, double& y) {
    x = a * b;
    y = std::fma(a, b, -x);
}

template <int N>
struct Expansion {
    std::array<double, N> c{};
    int n = 0;

    int sign() const { return n == 0 ? 0 : (c[static_cast<std::size_t>(n - 1)] > 0 ? 1 : -1); }
};

// Appends component h unless it is zero.
template <int N>
inline void push_nonzero(Expansion<N>& e, double h) {
    if (h != 0.0) {
        e.c[static_cast<std::size_t>(e.n++)] = h;
    }
}

// a - b as a two-component expansion.
inline Expansion<2> difference(double a, double b) {
    double x = 0.0;
    double y = 0.0;
    two_diff(a, b, x, y);
    Expansion<2> e;
    push_nonzero(e, y);
    push_nonzero(e, x);
    return e;
}

// e += b in place (Shewchuk's GROW-EXPANSION with zero elimination, Theorem 10: the result is
// again nonoverlapping and increasing). Requires e.n < N.
template <int N>
inline void grow(Expansion<N>& e, double b) {
    double q = b;
    int out = 0;
    for (int i = 0; i < e.n; ++i) {
        double h = 0.0;
        two_sum(q, e.c[static_cast<std::size_t>(i)], q, h);
        if (h != 0.0) {
            e.c[static_cast<std::size_t>(out++)] = h;  // out ≤ i: never overwrites unread input
        }
    }
    e.n = out;
    push_nonzero(e, q);
}

// e + f (Shewchuk's EXPANSION-SUM, Theorem 12, as one grow per component of f).
template <int N, int M>
inline Expansion<N + M> sum(const Expansion<N>& e, const Expansion<M>& f) {
    Expansion<N + M> h;
    for (int i = 0; i < e.n; ++i) {
        h.c[static_cast<std::size_t>(i)] = e.c[static_cast<std::size_t>(i)];
    }
    h.n = e.n;
    for (int j = 0; j < f.n; ++j) {
        grow(h, f.c[static_cast<std::size_t>(j)]);
    }
    return h;
}

template <int N>
inline Expansion<N> negated(Expansion<N> e) {
    for (int i = 0; i < e.n; ++i) {
        e.c[static_cast<std::size_t>(i)] = -e.c[static_cast<std::size_t>(i)];
    }
    return e;
}

// e · b (Shewchuk's SCALE-EXPANSION with zero elimination, Theorem 19; two_sum in place of his
// fast-two-sum gives the same outputs, without its precondition).
template <int N>
inline Expansion<2 * N> scale(const Expansion<N>& e, double b) {
    Expansion<2 * N> h;
    if (e.n == 0 || b == 0.0) {
        return h;
    }
    double q = 0.0;
    double low = 0.0;
    two_product(e.c[0], b, q, low);
    push_nonzero(h, low);
    for (int i = 1; i < e.n; ++i) {
        double product_high = 0.0;
        double product_low = 0.0;
        two_product(e.c[static_cast<std::size_t>(i)], b, product_high, product_low);
        double partial = 0.0;
        two_sum(q, product_low, partial, low);
        push_nonzero(h, low);
        two_sum(product_high, partial, q, low);
        push_nonzero(h, low);
    }
    push_nonzero(h, q);
    return h;
}

// e · f: the sum of e scaled by each component of f.
template <int N, int M>
inline Expansion<2 * N * M> product(const Expansion<N>& e, const Expansion<M>& f) {
    Expansion<2 * N * M> h;
    for (int j = 0; j < f.n; ++j) {
        const Expansion<2 * N> part = scale(e, f.c[static_cast<std::size_t>(j)]);
        for (int i = 0; i < part.n; ++i) {
            grow(h, part.c[static_cast<std::size_t>(i)]);
        }
    }
    return h;
}

int orient3d_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    const Expansion<2> ux = difference(b.x, a.x);
    const Expansion<2> uy = difference(b.y, a.y);
    const Expansion<2> uz = difference(b.z, a.z);
    const Expansion<2> vx = difference(c.x, a.x);
    const Expansion<2> vy = difference(c.y, a.y);
    const Expansion<2> vz = difference(c.z, a.z);
    const Expansion<2> wx = difference(d.x, a.x);
    const Expansion<2> wy = difference(d.y, a.y);
    const Expansion<2> wz = difference(d.z, a.z);
    // n = u × v, then n · w.
    const Expansion<16> nx = sum(product(uy, vz), negated(product(uz, vy)));
    const Expansion<16> ny = sum(product(uz, vx), negated(product(ux, vz)));
    const Expansion<16> nz = sum(product(ux, vy), negated(product(uy, vx)));
    return sum(sum(product(nx, wx), product(ny, wy)), product(nz, wz)).sign();
}

int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
    const Expansion<2> ux = difference(bx, ax);
    const Expansion<2> uy = difference(by, ay);
    const Expansion<2> vx = difference(cx, ax);
    const Expansion<2> vy = difference(cy, ay);
    return sum(product(ux, vy), negated(product(uy, vx))).sign();
}

}  // namespace

int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
    const double ux = b.x - a.x;
    const double uy = b.y - a.y;
    const double uz = b.z - a.z;
    const double vx = c.x - a.x;
    const double vy = c.y - a.y;
    const double vz = c.z - a.z;
    const double wx = d.x - a.x;
    const double wy = d.y - a.y;
    const double wz = d.z - a.z;
    const double p_yz = uy * vz;
    const double p_zy = uz * vy;
    const double p_zx = uz * vx;
    const double p_xz = ux * vz;
    const double p_xy = ux * vy;
    const double p_yx = uy * vx;
    const double det = wx * (p_yz - p_zy) + wy * (p_zx - p_xz) + wz * (p_xy - p_yx);
    const double permanent = std::fabs(wx) * (std::fabs(p_yz) + std::fabs(p_zy)) +
                             std::fabs(wy) * (std::fabs(p_zx) + std::fabs(p_xz)) +
                             std::fabs(wz) * (std::fabs(p_xy) + std::fabs(p_yx));
    if (permanent >= FILTER_MIN) {
        const double bound = ORIENT3D_BOUND * permanent;
        if (det > bound) {
            return 1;
        }
        if (-det > bound) {
            return -1;
        }
    }
    // Four points with one coordinate in common (a flat sheet in an axis plane, as generated
    // grids start) are coplanar: a row of the determinant is zero. The differences are exactly
    // zero just when the coordinates are equal (no flush to zero), so this decides exactly.
    if ((ux == 0.0 && vx == 0.0 && wx == 0.0) || (uy == 0.0 && vy == 0.0 && wy == 0.0) ||
        (uz == 0.0 && vz == 0.0 && wz == 0.0)) {
        return 0;
    }
    return orient3d_exact(a, b, c, d);
}

int orient2d(double ax, double ay, double bx, double by, double cx, double cy) {
    const double ux = bx - ax;
    const double uy = by - ay;
    const double vx = cx - ax;
    const double vy = cy - ay;
    const double p_xy = ux * vy;
    const double p_yx = uy * vx;
    const double det = p_xy - p_yx;
    const double permanent = std::fabs(p_xy) + std::fabs(p_yx);
    if (permanent >= FILTER_MIN) {
        const double bound = ORIENT2D_BOUND * permanent;
        if (det > bound) {
            return 1;
        }
        if (-det > bound) {
            return -1;
        }
    }
    // Both products exactly zero by a zero factor (points on one axis-parallel line, as along a
    // grid's rows): the determinant is zero, whatever the magnitudes.
    if ((ux == 0.0 || vy == 0.0) && (uy == 0.0 || vx == 0.0)) {
        return 0;
    }
    return orient2d_exact(ax, ay, bx, by, cx, cy);
}

}  // namespace pliant::geometry
