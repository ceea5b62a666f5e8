#include "pliant/cloth/detail/constraint_kernels.hpp"

#include <cmath>
#include <limits>

#include "pliant/core/simd_dispatch.hpp"

// The AVX2 kernels use no fma (core/simd_dispatch.hpp); pliant is compiled with -ffp-contract=off
// (cmake/PliantCodegen.cmake), so no a · b + c is contracted in the scalar kernels either.
#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

#include "pliant/core/simd_avx2.hpp"
#endif

namespace pliant::cloth::detail {
namespace {

// Cephes' atan (S. L. Moshier): atan(t) = t + t z P(z) / Q(z), z = t², for |t| ≤ 0.66.
constexpr double P0 = -8.750608600031904122785E-1;
constexpr double P1 = -1.615753718733365076637E1;
constexpr double P2 = -7.500855792314704667340E1;
constexpr double P3 = -1.228866684490136173410E2;
constexpr double P4 = -6.485021904942025371773E1;
constexpr double Q0 = 2.485846490142306297962E1;
constexpr double Q1 = 1.650270098316988542046E2;
constexpr double Q2 = 4.328810604912902668951E2;
constexpr double Q3 = 4.853903996359136964868E2;
constexpr double Q4 = 1.945506571482613964425E2;
constexpr double MOREBITS = 6.123233995736765886130E-17;  // π/2 − PI_2 (the double)
constexpr double PI_4 = 7.85398163397448309616E-1;
constexpr double PI_2 = 1.57079632679489661923E0;
constexpr double PI = 3.14159265358979323846E0;
constexpr double REDUCE = 0.66;
constexpr double TWO_PI = 2.0 * PI;

// The largest finite double: an edge longer than that (an overflow) takes no part in a chain.
constexpr double LARGEST = std::numeric_limits<double>::max();

// C = angle − rest wrapped into (−π, π] (both in (−π, π], so one turn at most).
inline double wrap(double c) {
    c = c > PI ? c - TWO_PI : c;
    return c <= -PI ? c + TWO_PI : c;
}

struct Vec {
    double x, y, z;
};
inline Vec sub(const Vec& a, const Vec& b) {
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec cross(const Vec& a, const Vec& b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double dot(const Vec& a, const Vec& b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec scale(const Vec& a, double s) {
    return {a.x * s, a.y * s, a.z * s};
}
inline Vec load(const PackedVertex& v) {
    return {v.x, v.y, v.z};
}

template <bool WITH_LAMBDA>
void stretch_scalar(PackedVertex* x, const StretchColumns& c, std::int64_t k, double alpha) {
    PackedVertex& a = x[c.p[k]];
    PackedVertex& b = x[c.q[k]];
    const double w = a.inverse_mass + b.inverse_mass;
    const double dx = a.x - b.x;
    const double dy = a.y - b.y;
    const double dz = a.z - b.z;
    const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(w > 0.0) || !(length > 0.0)) {
        return;
    }
    const double minus_c = -(length - c.rest_length[k]);
    const double lambda = (WITH_LAMBDA ? minus_c - alpha * c.lambda[k] : minus_c) / (w + alpha);
    const double inverse_length = 1.0 / length;
    const double gx = dx * inverse_length;
    const double gy = dy * inverse_length;
    const double gz = dz * inverse_length;
    const double sa = a.inverse_mass * lambda;
    const double sb = b.inverse_mass * lambda;
    a.x = a.x + gx * sa;
    a.y = a.y + gy * sa;
    a.z = a.z + gz * sa;
    b.x = b.x - gx * sb;
    b.y = b.y - gy * sb;
    b.z = b.z - gz * sb;
}

void bending_scalar(PackedVertex* x, const BendingColumns& c, std::int64_t k, double alpha) {
    PackedVertex& p0 = x[c.v0[k]];
    PackedVertex& p1 = x[c.v1[k]];
    PackedVertex& p2 = x[c.v2[k]];
    PackedVertex& p3 = x[c.v3[k]];
    const Vec x0 = load(p0);
    const Vec x1 = load(p1);
    const Vec x2 = load(p2);
    const Vec x3 = load(p3);
    const Vec e = sub(x3, x2);
    const Vec a0 = sub(x2, x0);
    const Vec a1 = sub(x3, x0);
    const Vec b0 = sub(x3, x1);
    const Vec b1 = sub(x2, x1);
    const Vec n_a = cross(a0, a1);
    const Vec n_b = cross(b0, b1);
    const double e2 = dot(e, e);
    const double na2 = dot(n_a, n_a);
    const double nb2 = dot(n_b, n_b);
    if (!(e2 > 0.0) || !(na2 > 0.0) || !(nb2 > 0.0)) {
        return;
    }
    const double length = std::sqrt(e2);
    const double inverse_length = 1.0 / length;
    // sin θ |n_a| |n_b| = (n_a × n_b) · ê, cos θ |n_a| |n_b| = n_a · n_b.
    const double sine = dot(cross(n_a, n_b), e) * inverse_length;
    const double cosine = dot(n_a, n_b);
    const double constraint = wrap(detail::atan2(sine, cosine) - c.rest_angle[k]);
    // ∇θ (dihedral.hpp): n_a / |n_a|² and n_b / |n_b|² times edge-length terms.
    const Vec sa = scale(n_a, 1.0 / na2);
    const Vec sb = scale(n_b, 1.0 / nb2);
    const double a0e = dot(a0, e) * inverse_length;
    const double a1e = dot(a1, e) * inverse_length;
    const double b0e = dot(b0, e) * inverse_length;
    const double b1e = dot(b1, e) * inverse_length;
    const double minus_length = -length;
    const Vec g0 = scale(sa, minus_length);
    const Vec g1 = scale(sb, minus_length);
    const Vec g2 = {sa.x * a1e + sb.x * b0e, sa.y * a1e + sb.y * b0e, sa.z * a1e + sb.z * b0e};
    const Vec g3 = {-(sa.x * a0e + sb.x * b1e), -(sa.y * a0e + sb.y * b1e),
                    -(sa.z * a0e + sb.z * b1e)};
    const double weight = p0.inverse_mass * dot(g0, g0) + p1.inverse_mass * dot(g1, g1) +
                          p2.inverse_mass * dot(g2, g2) + p3.inverse_mass * dot(g3, g3);
    if (!(weight > 0.0)) {
        return;
    }
    const double lambda = -constraint / (weight + alpha);
    const auto move = [lambda](PackedVertex& p, const Vec& g) {
        const double s = p.inverse_mass * lambda;
        p.x = p.x + g.x * s;
        p.y = p.y + g.y * s;
        p.z = p.z + g.z * s;
    };
    move(p0, g0);
    move(p1, g1);
    move(p2, g2);
    move(p3, g3);
}

void isometric_scalar(PackedVertex* x, const IsometricBendingColumns& c, std::int64_t k,
                      double alpha) {
    PackedVertex& p0 = x[c.v0[k]];
    PackedVertex& p1 = x[c.v1[k]];
    PackedVertex& p2 = x[c.v2[k]];
    PackedVertex& p3 = x[c.v3[k]];
    const double k0 = c.k0[k];
    const double k1 = c.k1[k];
    const double k2 = c.k2[k];
    const double k3 = c.k3[k];
    const Vec x2 = load(p2);
    const Vec d0 = sub(load(p0), x2);
    const Vec d1 = sub(load(p1), x2);
    const Vec d3 = sub(load(p3), x2);
    const Vec bend = {k0 * d0.x + k1 * d1.x + k3 * d3.x, k0 * d0.y + k1 * d1.y + k3 * d3.y,
                      k0 * d0.z + k1 * d1.z + k3 * d3.z};
    // n = K_0 n_A + K_1 n_B: n_A = (x2 − x0) × (x3 − x0) = d3 × d0,
    // n_B = (x3 − x1) × (x2 − x1) = d1 × d3.
    const Vec n_a = cross(d3, d0);
    const Vec n_b = cross(d1, d3);
    const Vec n = {k0 * n_a.x + k1 * n_b.x, k0 * n_a.y + k1 * n_b.y, k0 * n_a.z + k1 * n_b.z};
    const double weight = p0.inverse_mass * (k0 * k0) + p1.inverse_mass * (k1 * k1) +
                          p2.inverse_mass * (k2 * k2) + p3.inverse_mass * (k3 * k3);
    const double denominator = dot(n, n) * (weight + alpha);
    if (!(weight > 0.0) || !(denominator > 0.0)) {
        return;
    }
    // C = n̂ · bend, ∇_k C = K_k n̂: x_k += w_k K_k n̂ Δλ, Δλ = −C / (weight + α̃), so
    // n̂ Δλ = n · (−(n · bend) / (|n|² (weight + α̃))).
    const Vec lambda = scale(n, -dot(n, bend) / denominator);
    const auto move = [&lambda](PackedVertex& p, double stencil) {
        const double s = p.inverse_mass * stencil;
        p.x = p.x + lambda.x * s;
        p.y = p.y + lambda.y * s;
        p.z = p.z + lambda.z * s;
    };
    move(p0, k0);
    move(p1, k1);
    move(p2, k2);
    move(p3, k3);
}

// Scratch of a chain packet: per row of edges, six rows of four lanes: the edge direction n
// (x, y, z), the eliminated right-hand side r_k, the eliminated super-diagonal u_k, and whether
// the edge takes part.
enum ChainField { CHAIN_NX, CHAIN_NY, CHAIN_NZ, CHAIN_R, CHAIN_U, CHAIN_ACTIVE };
inline std::int64_t chain_slot(std::int32_t row, ChainField field) {
    return (6 * static_cast<std::int64_t>(row) + field) * 4;
}

// Lane `lane` of a chain packet. Forward sweep: per edge its direction and −C, the diagonal
// (w_k + w_{k+1}) (1 + ε + κ |C_k| / ℓ_k) + α̃, and the Thomas elimination: with ℓ_k = A_{k,k−1},
// u_{k−1} = ℓ_k / d_{k−1}, d_k = A_kk − ℓ_k u_{k−1}, r_k = (−C_k − ℓ_k r_{k−1}) / d_k (u and r 0 on
// an edge that takes no part). Backward sweep: Δλ_k = r_k − u_k Δλ_{k+1} (0 on an edge that takes
// no part), written to lambda[edge], and vertex k + 1 moves by w (n_k Δλ_k − n_{k+1} Δλ_{k+1}) as
// soon as both are known; vertex 0 last.
void chain_lane_scalar(PackedVertex* x, const ChainPacket& c, int lane, const ChainSolve& solve,
                       double* lambda_out, double* s) {
    const std::int32_t m = c.num_rows;
    const auto vertex = [&](std::int32_t row) -> PackedVertex& {
        return x[c.vertices[4 * static_cast<std::int64_t>(row) + lane]];
    };
    const double scale = 1.0 + solve.regularization;
    const double strain = solve.strain_regularization;
    const PackedVertex* p = &vertex(0);
    double pnx = 0.0;
    double pny = 0.0;
    double pnz = 0.0;
    double previous_inverse = 0.0;
    double previous_r = 0.0;
    for (std::int32_t k = 0; k < m; ++k) {
        const PackedVertex* q = &vertex(k + 1);
        const double dx = q->x - p->x;
        const double dy = q->y - p->y;
        const double dz = q->z - p->z;
        const double length = std::sqrt(dx * dx + dy * dy + dz * dz);
        const double w0 = p->inverse_mass;
        const double weight = w0 + q->inverse_mass;
        const double rest = c.rest_length[4 * static_cast<std::int64_t>(k) + lane];
        const bool active = weight > 0.0 && length > 0.0 && length <= LARGEST && rest >= 0.0;
        const double inverse_length = 1.0 / length;
        const double nx = active ? dx * inverse_length : 0.0;
        const double ny = active ? dy * inverse_length : 0.0;
        const double nz = active ? dz * inverse_length : 0.0;
        const double minus_c = active ? rest - length : 0.0;
        const double diagonal =
            active ? weight * (scale + strain * std::abs(minus_c) * inverse_length) + solve.alpha
                   : 1.0;
        const double lower = -(w0 * (pnx * nx + pny * ny + pnz * nz));
        const double u = active ? lower * previous_inverse : 0.0;
        const double inverse = 1.0 / (diagonal - lower * u);
        const double r = active ? (minus_c - lower * previous_r) * inverse : 0.0;
        if (k > 0) {
            s[chain_slot(k - 1, CHAIN_U) + lane] = u;
        }
        s[chain_slot(k, CHAIN_ACTIVE) + lane] = active ? 1.0 : 0.0;
        s[chain_slot(k, CHAIN_NX) + lane] = nx;
        s[chain_slot(k, CHAIN_NY) + lane] = ny;
        s[chain_slot(k, CHAIN_NZ) + lane] = nz;
        s[chain_slot(k, CHAIN_R) + lane] = r;
        pnx = nx;
        pny = ny;
        pnz = nz;
        previous_inverse = inverse;
        previous_r = r;
        p = q;
    }
    if (m > 0) {
        s[chain_slot(m - 1, CHAIN_U) + lane] = 0.0;
    }
    double next_lambda = 0.0;  // Δλ_{k+1}, and n_{k+1}
    double nnx = 0.0;
    double nny = 0.0;
    double nnz = 0.0;
    const auto move = [&](PackedVertex& v, double nx, double ny, double nz, double lambda) {
        v.x = v.x + v.inverse_mass * (nx * lambda - nnx * next_lambda);
        v.y = v.y + v.inverse_mass * (ny * lambda - nny * next_lambda);
        v.z = v.z + v.inverse_mass * (nz * lambda - nnz * next_lambda);
    };
    for (std::int32_t k = m - 1; k >= 0; --k) {
        const double lambda =
            s[chain_slot(k, CHAIN_ACTIVE) + lane] != 0.0
                ? s[chain_slot(k, CHAIN_R) + lane] - s[chain_slot(k, CHAIN_U) + lane] * next_lambda
                : 0.0;
        const std::int32_t edge = c.edges[4 * static_cast<std::int64_t>(k) + lane];
        if (edge >= 0) {
            lambda_out[edge] = lambda;
        }
        const double nx = s[chain_slot(k, CHAIN_NX) + lane];
        const double ny = s[chain_slot(k, CHAIN_NY) + lane];
        const double nz = s[chain_slot(k, CHAIN_NZ) + lane];
        move(vertex(k + 1), nx, ny, nz, lambda);
        next_lambda = lambda;
        nnx = nx;
        nny = ny;
        nnz = nz;
    }
    move(vertex(0), 0.0, 0.0, 0.0, 0.0);
}

#if defined(PLIANT_HAS_AVX2_TARGET)

using V = __m256d;

using simd::add;
using simd::div;
using simd::mul;
using simd::select;
using simd::set1;
using simd::sub;

PLIANT_AVX2_INLINE V greater(V a, V b) {
    return _mm256_cmp_pd(a, b, _CMP_GT_OQ);
}
PLIANT_AVX2_INLINE V less_equal(V a, V b) {
    return _mm256_cmp_pd(a, b, _CMP_LE_OQ);
}
PLIANT_AVX2_INLINE V absolute(V a) {
    return _mm256_andnot_pd(set1(-0.0), a);
}
// −a exactly as the scalar unary minus (0 − a would turn −0 into +0).
PLIANT_AVX2_INLINE V negate(V a) {
    return _mm256_xor_pd(set1(-0.0), a);
}

// x, y, z, inverse mass of four vertices, lane k = vertex k.
struct Lanes {
    V x, y, z, w;
};
struct Vec4 {
    V x, y, z;
};

// Rows r_k = vertex k, transposed into columns.
PLIANT_AVX2_INLINE Lanes load4(const PackedVertex* x, const std::int32_t* i) {
    const V r0 = _mm256_load_pd(&x[i[0]].x);
    const V r1 = _mm256_load_pd(&x[i[1]].x);
    const V r2 = _mm256_load_pd(&x[i[2]].x);
    const V r3 = _mm256_load_pd(&x[i[3]].x);
    const V t0 = _mm256_unpacklo_pd(r0, r1);  // x0 x1 z0 z1
    const V t1 = _mm256_unpackhi_pd(r0, r1);  // y0 y1 w0 w1
    const V t2 = _mm256_unpacklo_pd(r2, r3);  // x2 x3 z2 z3
    const V t3 = _mm256_unpackhi_pd(r2, r3);  // y2 y3 w2 w3
    return {_mm256_permute2f128_pd(t0, t2, 0x20), _mm256_permute2f128_pd(t1, t3, 0x20),
            _mm256_permute2f128_pd(t0, t2, 0x31), _mm256_permute2f128_pd(t1, t3, 0x31)};
}

// Writes x, y, z of lanes whose bit is set in `mask` (the inverse masses are unchanged).
PLIANT_AVX2_INLINE void store4(PackedVertex* x, const std::int32_t* i, const Lanes& l, int mask) {
    const V t0 = _mm256_unpacklo_pd(l.x, l.y);  // x0 y0 x2 y2
    const V t1 = _mm256_unpackhi_pd(l.x, l.y);  // x1 y1 x3 y3
    const V t2 = _mm256_unpacklo_pd(l.z, l.w);  // z0 w0 z2 w2
    const V t3 = _mm256_unpackhi_pd(l.z, l.w);  // z1 w1 z3 w3
    const V rows[4] = {_mm256_permute2f128_pd(t0, t2, 0x20), _mm256_permute2f128_pd(t1, t3, 0x20),
                       _mm256_permute2f128_pd(t0, t2, 0x31), _mm256_permute2f128_pd(t1, t3, 0x31)};
    for (int k = 0; k < 4; ++k) {
        if ((mask >> k) & 1) {
            _mm256_store_pd(&x[i[k]].x, rows[k]);
        }
    }
}

PLIANT_AVX2_INLINE Vec4 sub(const Lanes& a, const Lanes& b) {
    return {sub(a.x, b.x), sub(a.y, b.y), sub(a.z, b.z)};
}
// Part of the small vector algebra the kernels use; clang 14 calls it unused.
[[maybe_unused]] PLIANT_AVX2_INLINE Vec4 sub(const Vec4& a, const Vec4& b) {
    return {sub(a.x, b.x), sub(a.y, b.y), sub(a.z, b.z)};
}
PLIANT_AVX2_INLINE Vec4 cross(const Vec4& a, const Vec4& b) {
    return {sub(mul(a.y, b.z), mul(a.z, b.y)), sub(mul(a.z, b.x), mul(a.x, b.z)),
            sub(mul(a.x, b.y), mul(a.y, b.x))};
}
PLIANT_AVX2_INLINE V dot(const Vec4& a, const Vec4& b) {
    return add(add(mul(a.x, b.x), mul(a.y, b.y)), mul(a.z, b.z));
}
PLIANT_AVX2_INLINE Vec4 scale(const Vec4& a, V s) {
    return {mul(a.x, s), mul(a.y, s), mul(a.z, s)};
}

// detail::atan2, lane by lane.
PLIANT_AVX2_INLINE V atan2_4(V y, V x) {
    const V zero = _mm256_setzero_pd();
    const V ax = absolute(x);
    const V ay = absolute(y);
    const V swap = greater(ay, ax);
    const V num = select(swap, ax, ay);
    const V den = select(swap, ay, ax);
    const V t = select(greater(den, zero), div(num, den), zero);
    const V big = greater(t, set1(REDUCE));
    const V one = set1(1.0);
    const V t2 = select(big, div(sub(t, one), add(t, one)), t);
    const V z = mul(t2, t2);
    const V p =
        add(mul(add(mul(add(mul(add(mul(set1(P0), z), set1(P1)), z), set1(P2)), z), set1(P3)), z),
            set1(P4));
    const V q = add(
        mul(add(mul(add(mul(add(mul(add(z, set1(Q0)), z), set1(Q1)), z), set1(Q2)), z), set1(Q3)),
            z),
        set1(Q4));
    V r = add(mul(t2, div(mul(z, p), q)), t2);
    r = select(big, add(r, set1(0.5 * MOREBITS)), r);
    V a = add(select(big, set1(PI_4), zero), r);
    a = select(swap, add(sub(set1(PI_2), a), set1(MOREBITS)), a);
    a = select(_mm256_cmp_pd(x, zero, _CMP_LT_OQ), add(sub(set1(PI), a), set1(2.0 * MOREBITS)), a);
    return select(_mm256_cmp_pd(y, zero, _CMP_LT_OQ), sub(zero, a), a);
}

// p += g · (w λ), the scalar kernel's order.
PLIANT_AVX2_INLINE void move(Lanes& p, const Vec4& g, V lambda) {
    const V s = mul(p.w, lambda);
    p.x = add(p.x, mul(g.x, s));
    p.y = add(p.y, mul(g.y, s));
    p.z = add(p.z, mul(g.z, s));
}

PLIANT_AVX2_INLINE V wrap4(V c) {
    c = select(greater(c, set1(PI)), sub(c, set1(TWO_PI)), c);
    return select(less_equal(c, set1(-PI)), add(c, set1(TWO_PI)), c);
}

template <bool WITH_LAMBDA>
PLIANT_AVX2_INLINE void stretch_avx2(PackedVertex* x, const StretchColumns& c, std::int64_t k,
                                     V alpha) {
    Lanes a = load4(x, c.p + k);
    Lanes b = load4(x, c.q + k);
    const V zero = _mm256_setzero_pd();
    const V w = add(a.w, b.w);
    const V dx = sub(a.x, b.x);
    const V dy = sub(a.y, b.y);
    const V dz = sub(a.z, b.z);
    const V length = _mm256_sqrt_pd(add(add(mul(dx, dx), mul(dy, dy)), mul(dz, dz)));
    const int valid = _mm256_movemask_pd(_mm256_and_pd(greater(w, zero), greater(length, zero)));
    V minus_c = negate(sub(length, _mm256_loadu_pd(c.rest_length + k)));
    if constexpr (WITH_LAMBDA) {
        minus_c = sub(minus_c, mul(alpha, _mm256_loadu_pd(c.lambda + k)));
    }
    const V lambda = div(minus_c, add(w, alpha));
    const V inverse_length = div(set1(1.0), length);
    const V gx = mul(dx, inverse_length);
    const V gy = mul(dy, inverse_length);
    const V gz = mul(dz, inverse_length);
    const V sa = mul(a.w, lambda);
    const V sb = mul(b.w, lambda);
    a.x = add(a.x, mul(gx, sa));
    a.y = add(a.y, mul(gy, sa));
    a.z = add(a.z, mul(gz, sa));
    b.x = sub(b.x, mul(gx, sb));
    b.y = sub(b.y, mul(gy, sb));
    b.z = sub(b.z, mul(gz, sb));
    store4(x, c.p + k, a, valid);
    store4(x, c.q + k, b, valid);
}

PLIANT_AVX2_FN void bending_avx2(PackedVertex* x, const BendingColumns& c, std::int64_t k,
                                 V alpha) {
    Lanes p0 = load4(x, c.v0 + k);
    Lanes p1 = load4(x, c.v1 + k);
    Lanes p2 = load4(x, c.v2 + k);
    Lanes p3 = load4(x, c.v3 + k);
    const V zero = _mm256_setzero_pd();
    const Vec4 e = sub(p3, p2);
    const Vec4 a0 = sub(p2, p0);
    const Vec4 a1 = sub(p3, p0);
    const Vec4 b0 = sub(p3, p1);
    const Vec4 b1 = sub(p2, p1);
    const Vec4 n_a = cross(a0, a1);
    const Vec4 n_b = cross(b0, b1);
    const V e2 = dot(e, e);
    const V na2 = dot(n_a, n_a);
    const V nb2 = dot(n_b, n_b);
    const V shape_ok =
        _mm256_and_pd(_mm256_and_pd(greater(e2, zero), greater(na2, zero)), greater(nb2, zero));
    const V length = _mm256_sqrt_pd(e2);
    const V inverse_length = div(set1(1.0), length);
    const V sine = mul(dot(cross(n_a, n_b), e), inverse_length);
    const V cosine = dot(n_a, n_b);
    const V constraint = wrap4(sub(atan2_4(sine, cosine), _mm256_loadu_pd(c.rest_angle + k)));
    const Vec4 sa = scale(n_a, div(set1(1.0), na2));
    const Vec4 sb = scale(n_b, div(set1(1.0), nb2));
    const V a0e = mul(dot(a0, e), inverse_length);
    const V a1e = mul(dot(a1, e), inverse_length);
    const V b0e = mul(dot(b0, e), inverse_length);
    const V b1e = mul(dot(b1, e), inverse_length);
    const V minus_length = negate(length);
    const Vec4 g0 = scale(sa, minus_length);
    const Vec4 g1 = scale(sb, minus_length);
    const Vec4 g2 = {add(mul(sa.x, a1e), mul(sb.x, b0e)), add(mul(sa.y, a1e), mul(sb.y, b0e)),
                     add(mul(sa.z, a1e), mul(sb.z, b0e))};
    const Vec4 g3 = {negate(add(mul(sa.x, a0e), mul(sb.x, b1e))),
                     negate(add(mul(sa.y, a0e), mul(sb.y, b1e))),
                     negate(add(mul(sa.z, a0e), mul(sb.z, b1e)))};
    const V weight =
        add(add(add(mul(p0.w, dot(g0, g0)), mul(p1.w, dot(g1, g1))), mul(p2.w, dot(g2, g2))),
            mul(p3.w, dot(g3, g3)));
    const int valid = _mm256_movemask_pd(_mm256_and_pd(shape_ok, greater(weight, zero)));
    if (valid == 0) {
        return;
    }
    const V lambda = div(negate(constraint), add(weight, alpha));
    move(p0, g0, lambda);
    move(p1, g1, lambda);
    move(p2, g2, lambda);
    move(p3, g3, lambda);
    store4(x, c.v0 + k, p0, valid);
    store4(x, c.v1 + k, p1, valid);
    store4(x, c.v2 + k, p2, valid);
    store4(x, c.v3 + k, p3, valid);
}

PLIANT_AVX2_FN std::int64_t project_stretch_avx2(PackedVertex* x, const StretchColumns& c,
                                                 std::int64_t begin, std::int64_t end,
                                                 double alpha) {
    const V alpha4 = set1(alpha);
    // A local copy: the compiler then knows the kernel's stores to x leave the columns alone and
    // keeps their pointers in registers.
    const StretchColumns columns = c;
    std::int64_t k = begin;
    if (columns.lambda != nullptr) {
        for (; k + 4 <= end; k += 4) {
            stretch_avx2<true>(x, columns, k, alpha4);
        }
    } else {
        for (; k + 4 <= end; k += 4) {
            stretch_avx2<false>(x, columns, k, alpha4);
        }
    }
    return k;
}

// Helpers of isometric_avx2 as functions, not lambdas: a lambda does not inherit its enclosing
// function's target attribute, and without -march it would be compiled without AVX.
// k0 a + k1 b + k3 d, in the scalar kernel's order.
PLIANT_AVX2_INLINE V stencil_sum(V k0, V a, V k1, V b, V k3, V d) {
    return add(add(mul(k0, a), mul(k1, b)), mul(k3, d));
}
// p += λ (w stencil), λ a vector (the scalar kernel's order).
PLIANT_AVX2_INLINE void move_by_stencil(Lanes& p, const Vec4& lambda, V stencil) {
    const V s = mul(p.w, stencil);
    p.x = add(p.x, mul(lambda.x, s));
    p.y = add(p.y, mul(lambda.y, s));
    p.z = add(p.z, mul(lambda.z, s));
}

PLIANT_AVX2_INLINE void isometric_avx2(PackedVertex* x, const IsometricBendingColumns& c,
                                       std::int64_t k, V alpha) {
    Lanes p0 = load4(x, c.v0 + k);
    Lanes p1 = load4(x, c.v1 + k);
    Lanes p2 = load4(x, c.v2 + k);
    Lanes p3 = load4(x, c.v3 + k);
    const V k0 = _mm256_loadu_pd(c.k0 + k);
    const V k1 = _mm256_loadu_pd(c.k1 + k);
    const V k2 = _mm256_loadu_pd(c.k2 + k);
    const V k3 = _mm256_loadu_pd(c.k3 + k);
    const Vec4 d0 = sub(p0, p2);
    const Vec4 d1 = sub(p1, p2);
    const Vec4 d3 = sub(p3, p2);
    const Vec4 bend = {stencil_sum(k0, d0.x, k1, d1.x, k3, d3.x),
                       stencil_sum(k0, d0.y, k1, d1.y, k3, d3.y),
                       stencil_sum(k0, d0.z, k1, d1.z, k3, d3.z)};
    const Vec4 n_a = cross(d3, d0);
    const Vec4 n_b = cross(d1, d3);
    const Vec4 n = {add(mul(k0, n_a.x), mul(k1, n_b.x)), add(mul(k0, n_a.y), mul(k1, n_b.y)),
                    add(mul(k0, n_a.z), mul(k1, n_b.z))};
    const V weight =
        add(add(add(mul(p0.w, mul(k0, k0)), mul(p1.w, mul(k1, k1))), mul(p2.w, mul(k2, k2))),
            mul(p3.w, mul(k3, k3)));
    const V denominator = mul(dot(n, n), add(weight, alpha));
    const V zero = _mm256_setzero_pd();
    const int valid =
        _mm256_movemask_pd(_mm256_and_pd(greater(weight, zero), greater(denominator, zero)));
    if (valid == 0) {
        return;
    }
    const Vec4 lambda = scale(n, div(negate(dot(n, bend)), denominator));
    move_by_stencil(p0, lambda, k0);
    move_by_stencil(p1, lambda, k1);
    move_by_stencil(p2, lambda, k2);
    move_by_stencil(p3, lambda, k3);
    store4(x, c.v0 + k, p0, valid);
    store4(x, c.v1 + k, p1, valid);
    store4(x, c.v2 + k, p2, valid);
    store4(x, c.v3 + k, p3, valid);
}

PLIANT_AVX2_FN std::int64_t project_isometric_avx2(PackedVertex* x,
                                                   const IsometricBendingColumns& c,
                                                   std::int64_t begin, std::int64_t end,
                                                   double alpha) {
    const V alpha4 = set1(alpha);
    const IsometricBendingColumns columns = c;  // in registers, as in project_stretch_avx2
    std::int64_t k = begin;
    for (; k + 4 <= end; k += 4) {
        isometric_avx2(x, columns, k, alpha4);
    }
    return k;
}

PLIANT_AVX2_FN std::int64_t project_bending_avx2(PackedVertex* x, const BendingColumns& c,
                                                 std::int64_t begin, std::int64_t end,
                                                 double alpha) {
    const V alpha4 = set1(alpha);
    std::int64_t k = begin;
    for (; k + 4 <= end; k += 4) {
        bending_avx2(x, c, k, alpha4);
    }
    return k;
}

// The four lanes of chain_lane_scalar at once (same operations, same order).
PLIANT_AVX2_FN void project_chain_packet_avx2(PackedVertex* x, const ChainPacket& c,
                                              const ChainSolve& solve, double* lambda_out,
                                              double* s) {
    const std::int32_t m = c.num_rows;
    const V zero = _mm256_setzero_pd();
    const V one = set1(1.0);
    const V alpha = set1(solve.alpha);
    const V scale = set1(1.0 + solve.regularization);
    const V strain = set1(solve.strain_regularization);
    const V largest = set1(LARGEST);
    Lanes p = load4(x, c.vertices);
    V pnx = zero;
    V pny = zero;
    V pnz = zero;
    V previous_inverse = zero;
    V previous_r = zero;
    for (std::int32_t k = 0; k < m; ++k) {
        const Lanes q = load4(x, c.vertices + 4 * static_cast<std::int64_t>(k + 1));
        const V dx = sub(q.x, p.x);
        const V dy = sub(q.y, p.y);
        const V dz = sub(q.z, p.z);
        const V length = _mm256_sqrt_pd(add(add(mul(dx, dx), mul(dy, dy)), mul(dz, dz)));
        const V weight = add(p.w, q.w);
        const V rest = _mm256_loadu_pd(c.rest_length + 4 * static_cast<std::int64_t>(k));
        const V active = _mm256_and_pd(
            _mm256_and_pd(greater(weight, zero), greater(length, zero)),
            _mm256_and_pd(less_equal(length, largest), _mm256_cmp_pd(rest, zero, _CMP_GE_OQ)));
        const V inverse_length = div(one, length);
        const V nx = select(active, mul(dx, inverse_length), zero);
        const V ny = select(active, mul(dy, inverse_length), zero);
        const V nz = select(active, mul(dz, inverse_length), zero);
        const V minus_c = select(active, sub(rest, length), zero);
        const V diagonal =
            select(active,
                   add(mul(weight, add(scale, mul(mul(strain, absolute(minus_c)), inverse_length))),
                       alpha),
                   one);
        const V lower = negate(mul(p.w, add(add(mul(pnx, nx), mul(pny, ny)), mul(pnz, nz))));
        const V u = select(active, mul(lower, previous_inverse), zero);
        const V inverse = div(one, sub(diagonal, mul(lower, u)));
        const V r = select(active, mul(sub(minus_c, mul(lower, previous_r)), inverse), zero);
        if (k > 0) {
            _mm256_storeu_pd(s + chain_slot(k - 1, CHAIN_U), u);
        }
        _mm256_storeu_pd(s + chain_slot(k, CHAIN_ACTIVE), active);
        _mm256_storeu_pd(s + chain_slot(k, CHAIN_NX), nx);
        _mm256_storeu_pd(s + chain_slot(k, CHAIN_NY), ny);
        _mm256_storeu_pd(s + chain_slot(k, CHAIN_NZ), nz);
        _mm256_storeu_pd(s + chain_slot(k, CHAIN_R), r);
        pnx = nx;
        pny = ny;
        pnz = nz;
        previous_inverse = inverse;
        previous_r = r;
        p = q;
    }
    if (m > 0) {
        _mm256_storeu_pd(s + chain_slot(m - 1, CHAIN_U), zero);
    }
    V next_lambda = zero;
    V nnx = zero;
    V nny = zero;
    V nnz = zero;
    alignas(32) double lanes[4];
    for (std::int32_t k = m - 1; k >= -1; --k) {
        V lambda = zero;
        V nx = zero;
        V ny = zero;
        V nz = zero;
        if (k >= 0) {
            lambda = select(_mm256_loadu_pd(s + chain_slot(k, CHAIN_ACTIVE)),
                            sub(_mm256_loadu_pd(s + chain_slot(k, CHAIN_R)),
                                mul(_mm256_loadu_pd(s + chain_slot(k, CHAIN_U)), next_lambda)),
                            zero);
            _mm256_store_pd(lanes, lambda);
            const std::int32_t* edges = c.edges + 4 * static_cast<std::int64_t>(k);
            for (int l = 0; l < 4; ++l) {
                if (edges[l] >= 0) {
                    lambda_out[edges[l]] = lanes[l];
                }
            }
            nx = _mm256_loadu_pd(s + chain_slot(k, CHAIN_NX));
            ny = _mm256_loadu_pd(s + chain_slot(k, CHAIN_NY));
            nz = _mm256_loadu_pd(s + chain_slot(k, CHAIN_NZ));
        }
        const std::int32_t* row = c.vertices + 4 * static_cast<std::int64_t>(k + 1);
        Lanes v = load4(x, row);
        v.x = add(v.x, mul(v.w, sub(mul(nx, lambda), mul(nnx, next_lambda))));
        v.y = add(v.y, mul(v.w, sub(mul(ny, lambda), mul(nny, next_lambda))));
        v.z = add(v.z, mul(v.w, sub(mul(nz, lambda), mul(nnz, next_lambda))));
        store4(x, row, v, 0xF);
        next_lambda = lambda;
        nnx = nx;
        nny = ny;
        nnz = nz;
    }
}

#endif  // PLIANT_HAS_AVX2_TARGET

}  // namespace

double atan2(double y, double x) {
    const double ax = std::fabs(x);
    const double ay = std::fabs(y);
    const bool swap = ay > ax;
    const double num = swap ? ax : ay;
    const double den = swap ? ay : ax;
    const double t = den > 0.0 ? num / den : 0.0;
    const bool big = t > REDUCE;
    const double t2 = big ? (t - 1.0) / (t + 1.0) : t;
    const double z = t2 * t2;
    const double p = (((P0 * z + P1) * z + P2) * z + P3) * z + P4;
    const double q = ((((z + Q0) * z + Q1) * z + Q2) * z + Q3) * z + Q4;
    double r = t2 * (z * p / q) + t2;
    r = big ? r + 0.5 * MOREBITS : r;
    double a = (big ? PI_4 : 0.0) + r;
    a = swap ? (PI_2 - a) + MOREBITS : a;
    a = x < 0.0 ? (PI - a) + 2.0 * MOREBITS : a;
    return y < 0.0 ? 0.0 - a : a;
}

void project_stretch(PackedVertex* x, const StretchColumns& c, std::int64_t begin, std::int64_t end,
                     double alpha) {
    std::int64_t k = begin;
#if defined(PLIANT_HAS_AVX2_TARGET)
    if (has_avx2()) {
        k = project_stretch_avx2(x, c, begin, end, alpha);
    }
#endif
    for (; k < end; ++k) {
        if (c.lambda != nullptr) {
            stretch_scalar<true>(x, c, k, alpha);
        } else {
            stretch_scalar<false>(x, c, k, alpha);
        }
    }
}

void project_bending(PackedVertex* x, const BendingColumns& c, std::int64_t begin, std::int64_t end,
                     double alpha) {
    std::int64_t k = begin;
#if defined(PLIANT_HAS_AVX2_TARGET)
    if (has_avx2()) {
        k = project_bending_avx2(x, c, begin, end, alpha);
    }
#endif
    for (; k < end; ++k) {
        bending_scalar(x, c, k, alpha);
    }
}

void project_isometric_bending(PackedVertex* x, const IsometricBendingColumns& c,
                               std::int64_t begin, std::int64_t end, double alpha) {
    std::int64_t k = begin;
#if defined(PLIANT_HAS_AVX2_TARGET)
    if (has_avx2()) {
        k = project_isometric_avx2(x, c, begin, end, alpha);
    }
#endif
    for (; k < end; ++k) {
        isometric_scalar(x, c, k, alpha);
    }
}

void project_chain_packet(PackedVertex* x, const ChainPacket& packet, const ChainSolve& solve,
                          double* lambda, double* scratch) {
#if defined(PLIANT_HAS_AVX2_TARGET)
    if (has_avx2()) {
        project_chain_packet_avx2(x, packet, solve, lambda, scratch);
        return;
    }
#endif
    for (int lane = 0; lane < 4; ++lane) {
        chain_lane_scalar(x, packet, lane, solve, lambda, scratch);
    }
}

}  // namespace pliant::cloth::detail
