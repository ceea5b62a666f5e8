// The XPBD projections of one edge-distance and one tet-volume constraint (soft_body.hpp has the
// formulas), on positions packed with the substep's inverse mass: Float4 {x, y, z, w}, so that one
// 16-byte load fetches all a constraint needs of a vertex. Scalar kernels (any backend) and SSE
// kernels doing 4 constraints of one colour at once (their vertices must be distinct).
//
// inv_k = 1 / stiffness; alpha = α_phys / h² (XPBD's α̃ without the stiffness part). A constraint
// whose vertices all have w = 0, or whose gradient vanishes (zero-length edge, flat tet with
// coincident vertices), is skipped: its vertices keep their bits.
//
// The tet kernels also report the tets at risk of inversion for the guard (soft_body.hpp,
// "Inversion guard"): those whose volume before their projection is below AT_RISK_RATIO · V0 (V0
// the rest volume passed in; the same float comparison in every kernel, so every width flags the
// same tets).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "pliant/core/host_device.hpp"
#include "pliant/geometry/tet_mesh.hpp"

#if defined(__SSE2__)
#include <immintrin.h>
#define PLIANT_PBD_SSE 1
#endif

namespace pliant::pbd::detail {

struct alignas(16) Float4 {
    float x, y, z, w;
};

// Inversion guard (soft_body.hpp): a tet is at risk below AT_RISK_RATIO · V0 (before its
// projection in the sweep, or after the guard); the guard lifts it to GUARD_RATIO · V0.
inline constexpr float AT_RISK_RATIO = 0.75f;
inline constexpr float GUARD_RATIO = 0.1f;
// Passes of guard_tet over the flagged tets at most; the guard stops after a pass that moved none.
inline constexpr int GUARD_PASSES = 16;

// C = |x_a − x_b| − rest_length; ∇_a C = n = (x_a − x_b) / |x_a − x_b| = −∇_b C.
PLIANT_HOST_DEVICE inline void project_edge(Float4* x, std::int32_t a, std::int32_t b,
                                            float rest_length, float inv_k, float alpha) {
    const Float4 pa = x[a];
    const Float4 pb = x[b];
    const float w = pa.w + pb.w;
    const float dx = pa.x - pb.x;
    const float dy = pa.y - pb.y;
    const float dz = pa.z - pb.z;
    const float length = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(w > 0.0f) || !(length > 0.0f)) {
        return;
    }
    // s = Δλ / |x_a − x_b| with Δλ = −C / (w / k + α) as one division. 0 − a rather than −a,
    // here and below: the SIMD kernels' arithmetic, to the sign of a zero.
    const float s = (0.0f - (length - rest_length)) / ((w * inv_k + alpha) * length);
    const float sa = pa.w * s;
    const float sb = pb.w * s;
    x[a] = {pa.x + sa * dx, pa.y + sa * dy, pa.z + sa * dz, pa.w};
    x[b] = {pb.x - sb * dx, pb.y - sb * dy, pb.z - sb * dz, pb.w};
}

// V = e1 · (e2 × e3) / 6 of tet (p[0], p[1], p[2], p[3]) with e_k = p_k − p_0, its gradients
// ∇_1 V = e2 × e3 / 6, ∇_2 V = e3 × e1 / 6, ∇_3 V = e1 × e2 / 6, ∇_0 V = −(∇_1 + ∇_2 + ∇_3)
// (Müller et al. 2007, eq. 16), and weight = Σ_k w_k |∇_k V|².
struct TetGradient {
    float volume = 0.0f;
    float weight = 0.0f;
    float gx[4]{}, gy[4]{}, gz[4]{};
};
// The gradients' cross products times scale, the volume e1 · (scaled ∇_1) and the weight from
// them: scale 1/6 gives V and ∇_k V (tet_gradient), scale 1 gives 6 V and ∇_k (6 V)
// (tet_gradient6; x · 1 is x, so its bits are those of the unscaled products).
PLIANT_HOST_DEVICE inline TetGradient scaled_tet_gradient(const Float4 (&p)[4], float scale) {
    const float e1x = p[1].x - p[0].x, e1y = p[1].y - p[0].y, e1z = p[1].z - p[0].z;
    const float e2x = p[2].x - p[0].x, e2y = p[2].y - p[0].y, e2z = p[2].z - p[0].z;
    const float e3x = p[3].x - p[0].x, e3y = p[3].y - p[0].y, e3z = p[3].z - p[0].z;
    TetGradient g;
    g.gx[1] = (e2y * e3z - e2z * e3y) * scale;
    g.gy[1] = (e2z * e3x - e2x * e3z) * scale;
    g.gz[1] = (e2x * e3y - e2y * e3x) * scale;
    g.gx[2] = (e3y * e1z - e3z * e1y) * scale;
    g.gy[2] = (e3z * e1x - e3x * e1z) * scale;
    g.gz[2] = (e3x * e1y - e3y * e1x) * scale;
    g.gx[3] = (e1y * e2z - e1z * e2y) * scale;
    g.gy[3] = (e1z * e2x - e1x * e2z) * scale;
    g.gz[3] = (e1x * e2y - e1y * e2x) * scale;
    g.gx[0] = 0.0f - (g.gx[1] + g.gx[2] + g.gx[3]);
    g.gy[0] = 0.0f - (g.gy[1] + g.gy[2] + g.gy[3]);
    g.gz[0] = 0.0f - (g.gz[1] + g.gz[2] + g.gz[3]);
    g.volume = e1x * g.gx[1] + e1y * g.gy[1] + e1z * g.gz[1];
    const auto norm2 = [&](int k) {
        return g.gx[k] * g.gx[k] + g.gy[k] * g.gy[k] + g.gz[k] * g.gz[k];
    };
    g.weight = p[0].w * norm2(0) + p[1].w * norm2(1) + p[2].w * norm2(2) + p[3].w * norm2(3);
    return g;
}
PLIANT_HOST_DEVICE inline TetGradient tet_gradient(const Float4 (&p)[4]) {
    constexpr float SIXTH = 1.0f / 6.0f;
    return scaled_tet_gradient(p, SIXTH);
}

// x_k += w_k ∇_k V Δλ for the vertices of tet t, loaded as p.
PLIANT_HOST_DEVICE inline void move_tet(Float4* x, const geometry::Tet& t, const Float4 (&p)[4],
                                        const TetGradient& g, float dlambda) {
    for (int k = 0; k < 4; ++k) {
        const float s = p[k].w * dlambda;
        x[t[static_cast<std::size_t>(k)]] = {p[k].x + s * g.gx[k], p[k].y + s * g.gy[k],
                                             p[k].z + s * g.gz[k], p[k].w};
    }
}

// tet_gradient's quantities for 6 V: volume = 6 V = e1 · (e2 × e3), gradients ∇_k (6 V) (e2 × e3,
// e3 × e1, e1 × e2, minus their sum), weight = Σ_k w_k |∇_k (6 V)|² (= 36 Σ_k w_k |∇_k V|²): the
// projection's form, without the 9 products by 1/6.
PLIANT_HOST_DEVICE inline TetGradient tet_gradient6(const Float4 (&p)[4]) {
    return scaled_tet_gradient(p, 1.0f);
}

// C = V − V0, projected as the equivalent C' = 6 C (tet_gradient6): Δx_k = w_k ∇_k C' Δλ' with
// Δλ' = −C' / (Σ_k w_k |∇_k C'|² / k + 36 α) moves every vertex as Δλ = −C / (Σ_k w_k |∇_k V|² / k
// + α) does with ∇_k V (the factors 6 and 36 cancel), for 9 products fewer. alpha36 = 36 α
// (tet_alpha36). Returns whether the tet is at risk (6 V below AT_RISK_RATIO · 6 V0 before the
// projection).
PLIANT_HOST_DEVICE inline float tet_alpha36(float alpha) {
    return alpha * 36.0f;
}
PLIANT_HOST_DEVICE inline bool project_tet(Float4* x, const geometry::Tet& t, float rest_volume,
                                           float inv_k, float alpha) {
    const Float4 p[4] = {x[t[0]], x[t[1]], x[t[2]], x[t[3]]};
    const TetGradient g = tet_gradient6(p);
    const float rest6 = rest_volume * 6.0f;
    const bool at_risk = g.volume < rest6 * AT_RISK_RATIO;
    if (!(g.weight > 0.0f)) {
        return at_risk;
    }
    move_tet(x, t, p, g, (0.0f - (g.volume - rest6)) / (g.weight * inv_k + tet_alpha36(alpha)));
    return at_risk;
}

// V of tet t (tet_gradient's arithmetic).
PLIANT_HOST_DEVICE inline float tet_volume(const Float4* x, const geometry::Tet& t) {
    const Float4 p[4] = {x[t[0]], x[t[1]], x[t[2]], x[t[3]]};
    return tet_gradient(p).volume;
}

// The inversion guard's projection (soft_body.hpp): the unilateral constraint
// C = V − GUARD_RATIO · V0 ≥ 0, projected only when violated, as a hard constraint (no stiffness,
// no compliance), and only for V0 > 0 (a rest-state driver may ask for an inverted rest shape).
// Returns whether it moved the tet.
PLIANT_HOST_DEVICE inline bool guard_tet(Float4* x, const geometry::Tet& t, float rest_volume) {
    const float min_volume = rest_volume * GUARD_RATIO;
    const Float4 p[4] = {x[t[0]], x[t[1]], x[t[2]], x[t[3]]};
    const TetGradient g = tet_gradient(p);
    if (!(rest_volume > 0.0f) || !(g.volume < min_volume) || !(g.weight > 0.0f)) {
        return false;
    }
    move_tet(x, t, p, g, (min_volume - g.volume) / g.weight);
    return true;
}

#if defined(PLIANT_PBD_SSE)

// Loads x[i0..i3] and transposes them into lanes: (xs, ys, zs, ws).
struct Lanes {
    __m128 x, y, z, w;
};
inline Lanes load_lanes(const Float4* x, std::int32_t i0, std::int32_t i1, std::int32_t i2,
                        std::int32_t i3) {
    Lanes l{_mm_load_ps(&x[i0].x), _mm_load_ps(&x[i1].x), _mm_load_ps(&x[i2].x),
            _mm_load_ps(&x[i3].x)};
    _MM_TRANSPOSE4_PS(l.x, l.y, l.z, l.w);
    return l;
}
inline void store_lanes(Float4* x, std::int32_t i0, std::int32_t i1, std::int32_t i2,
                        std::int32_t i3, Lanes l) {
    _MM_TRANSPOSE4_PS(l.x, l.y, l.z, l.w);
    _mm_store_ps(&x[i0].x, l.x);
    _mm_store_ps(&x[i1].x, l.y);
    _mm_store_ps(&x[i2].x, l.z);
    _mm_store_ps(&x[i3].x, l.w);
}

// Four edges e[0..3] of one colour (no shared vertex), the arithmetic of project_edge per lane.
inline void project_edges4(Float4* x, const std::array<std::int32_t, 2>* e,
                           const float* rest_lengths, float inv_k, float alpha) {
    Lanes a = load_lanes(x, e[0][0], e[1][0], e[2][0], e[3][0]);
    Lanes b = load_lanes(x, e[0][1], e[1][1], e[2][1], e[3][1]);
    const __m128 w = _mm_add_ps(a.w, b.w);
    const __m128 dx = _mm_sub_ps(a.x, b.x);
    const __m128 dy = _mm_sub_ps(a.y, b.y);
    const __m128 dz = _mm_sub_ps(a.z, b.z);
    const __m128 length = _mm_sqrt_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
    const __m128 zero = _mm_setzero_ps();
    const __m128 valid = _mm_and_ps(_mm_cmpgt_ps(w, zero), _mm_cmpgt_ps(length, zero));
    const __m128 denominator = _mm_add_ps(_mm_mul_ps(w, _mm_set1_ps(inv_k)), _mm_set1_ps(alpha));
    const __m128 violation = _mm_sub_ps(length, _mm_loadu_ps(rest_lengths));
    const __m128 s =
        _mm_and_ps(valid, _mm_div_ps(_mm_sub_ps(zero, violation), _mm_mul_ps(denominator, length)));
    const __m128 sa = _mm_mul_ps(a.w, s);
    const __m128 sb = _mm_mul_ps(b.w, s);
    a.x = _mm_add_ps(a.x, _mm_mul_ps(sa, dx));
    a.y = _mm_add_ps(a.y, _mm_mul_ps(sa, dy));
    a.z = _mm_add_ps(a.z, _mm_mul_ps(sa, dz));
    b.x = _mm_sub_ps(b.x, _mm_mul_ps(sb, dx));
    b.y = _mm_sub_ps(b.y, _mm_mul_ps(sb, dy));
    b.z = _mm_sub_ps(b.z, _mm_mul_ps(sb, dz));
    store_lanes(x, e[0][0], e[1][0], e[2][0], e[3][0], a);
    store_lanes(x, e[0][1], e[1][1], e[2][1], e[3][1], b);
}

// Four tets t[0..3] of one colour (no shared vertex), the arithmetic of project_tet per lane
// (tet_gradient6).
// Returns the tets at risk as a mask (bit l: t[l]).
inline int project_tets4(Float4* x, const geometry::Tet* t, const float* rest_volumes, float inv_k,
                         float alpha) {
    Lanes p0 = load_lanes(x, t[0][0], t[1][0], t[2][0], t[3][0]);
    Lanes p1 = load_lanes(x, t[0][1], t[1][1], t[2][1], t[3][1]);
    Lanes p2 = load_lanes(x, t[0][2], t[1][2], t[2][2], t[3][2]);
    Lanes p3 = load_lanes(x, t[0][3], t[1][3], t[2][3], t[3][3]);
    const auto sub = [](__m128 u, __m128 v) {
        return _mm_sub_ps(u, v);
    };
    const auto mul = [](__m128 u, __m128 v) {
        return _mm_mul_ps(u, v);
    };
    const auto add = [](__m128 u, __m128 v) {
        return _mm_add_ps(u, v);
    };
    const __m128 e1x = sub(p1.x, p0.x), e1y = sub(p1.y, p0.y), e1z = sub(p1.z, p0.z);
    const __m128 e2x = sub(p2.x, p0.x), e2y = sub(p2.y, p0.y), e2z = sub(p2.z, p0.z);
    const __m128 e3x = sub(p3.x, p0.x), e3y = sub(p3.y, p0.y), e3z = sub(p3.z, p0.z);
    const __m128 g1x = sub(mul(e2y, e3z), mul(e2z, e3y));
    const __m128 g1y = sub(mul(e2z, e3x), mul(e2x, e3z));
    const __m128 g1z = sub(mul(e2x, e3y), mul(e2y, e3x));
    const __m128 g2x = sub(mul(e3y, e1z), mul(e3z, e1y));
    const __m128 g2y = sub(mul(e3z, e1x), mul(e3x, e1z));
    const __m128 g2z = sub(mul(e3x, e1y), mul(e3y, e1x));
    const __m128 g3x = sub(mul(e1y, e2z), mul(e1z, e2y));
    const __m128 g3y = sub(mul(e1z, e2x), mul(e1x, e2z));
    const __m128 g3z = sub(mul(e1x, e2y), mul(e1y, e2x));
    const __m128 zero = _mm_setzero_ps();
    const __m128 g0x = sub(zero, add(add(g1x, g2x), g3x));
    const __m128 g0y = sub(zero, add(add(g1y, g2y), g3y));
    const __m128 g0z = sub(zero, add(add(g1z, g2z), g3z));
    const __m128 volume = add(add(mul(e1x, g1x), mul(e1y, g1y)), mul(e1z, g1z));
    const auto norm2 = [&](__m128 u, __m128 v, __m128 s) {
        return add(add(mul(u, u), mul(v, v)), mul(s, s));
    };
    const __m128 weight =
        add(add(add(mul(p0.w, norm2(g0x, g0y, g0z)), mul(p1.w, norm2(g1x, g1y, g1z))),
                mul(p2.w, norm2(g2x, g2y, g2z))),
            mul(p3.w, norm2(g3x, g3y, g3z)));
    const __m128 rest = mul(_mm_loadu_ps(rest_volumes), _mm_set1_ps(6.0f));
    const int at_risk =
        _mm_movemask_ps(_mm_cmplt_ps(volume, mul(rest, _mm_set1_ps(AT_RISK_RATIO))));
    const __m128 valid = _mm_cmpgt_ps(weight, zero);
    const __m128 denominator =
        add(mul(weight, _mm_set1_ps(inv_k)), _mm_set1_ps(tet_alpha36(alpha)));
    const __m128 violation = sub(volume, rest);
    const __m128 dlambda = _mm_and_ps(valid, _mm_div_ps(sub(zero, violation), denominator));
    const __m128 s0 = mul(p0.w, dlambda);
    const __m128 s1 = mul(p1.w, dlambda);
    const __m128 s2 = mul(p2.w, dlambda);
    const __m128 s3 = mul(p3.w, dlambda);
    p0.x = add(p0.x, mul(s0, g0x)), p0.y = add(p0.y, mul(s0, g0y)), p0.z = add(p0.z, mul(s0, g0z));
    p1.x = add(p1.x, mul(s1, g1x)), p1.y = add(p1.y, mul(s1, g1y)), p1.z = add(p1.z, mul(s1, g1z));
    p2.x = add(p2.x, mul(s2, g2x)), p2.y = add(p2.y, mul(s2, g2y)), p2.z = add(p2.z, mul(s2, g2z));
    p3.x = add(p3.x, mul(s3, g3x)), p3.y = add(p3.y, mul(s3, g3y)), p3.z = add(p3.z, mul(s3, g3z));
    store_lanes(x, t[0][0], t[1][0], t[2][0], t[3][0], p0);
    store_lanes(x, t[0][1], t[1][1], t[2][1], t[3][1], p1);
    store_lanes(x, t[0][2], t[1][2], t[2][2], t[3][2], p2);
    store_lanes(x, t[0][3], t[1][3], t[2][3], t[3][3], p3);
    return at_risk;
}

#endif  // PLIANT_PBD_SSE

}  // namespace pliant::pbd::detail
