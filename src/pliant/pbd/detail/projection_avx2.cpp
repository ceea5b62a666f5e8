#include "pliant/pbd/detail/projection_avx2.hpp"

#include <algorithm>

#include "pliant/core/simd_dispatch.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

#include "pliant/core/simd_avx2.hpp"
#endif

namespace pliant::pbd::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

// x, y, z, w of 8 vertices, lane k = vertex k.
struct Lanes8 {
    __m256 x, y, z, w;
};

// Rows r0 = [v0 | v4], r1 = [v1 | v5], r2 = [v2 | v6], r3 = [v3 | v7] of Float4s, transposed per
// 128-bit half into x = [x0 x1 x2 x3 | x4 x5 x6 x7] and likewise y, z, w.
PLIANT_AVX2_INLINE __m256 row(const Float4& lo, const Float4& hi) {
    return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(&lo.x)), _mm_load_ps(&hi.x), 1);
}
PLIANT_AVX2_INLINE Lanes8 load8(const Float4* x, const std::int32_t* i) {
    const __m256 r0 = row(x[i[0]], x[i[4]]);
    const __m256 r1 = row(x[i[1]], x[i[5]]);
    const __m256 r2 = row(x[i[2]], x[i[6]]);
    const __m256 r3 = row(x[i[3]], x[i[7]]);
    const __m256 t0 = _mm256_unpacklo_ps(r0, r1);  // x0 x1 y0 y1
    const __m256 t1 = _mm256_unpacklo_ps(r2, r3);  // x2 x3 y2 y3
    const __m256 t2 = _mm256_unpackhi_ps(r0, r1);  // z0 z1 w0 w1
    const __m256 t3 = _mm256_unpackhi_ps(r2, r3);  // z2 z3 w2 w3
    return {_mm256_shuffle_ps(t0, t1, 0x44), _mm256_shuffle_ps(t0, t1, 0xEE),
            _mm256_shuffle_ps(t2, t3, 0x44), _mm256_shuffle_ps(t2, t3, 0xEE)};
}

PLIANT_AVX2_INLINE void store8(Float4* x, const std::int32_t* i, const Lanes8& l) {
    const __m256 t0 = _mm256_unpacklo_ps(l.x, l.y);  // x0 y0 x1 y1
    const __m256 t1 = _mm256_unpacklo_ps(l.z, l.w);  // z0 w0 z1 w1
    const __m256 t2 = _mm256_unpackhi_ps(l.x, l.y);  // x2 y2 x3 y3
    const __m256 t3 = _mm256_unpackhi_ps(l.z, l.w);  // z2 w2 z3 w3
    const __m256 r0 = _mm256_shuffle_ps(t0, t1, 0x44);
    const __m256 r1 = _mm256_shuffle_ps(t0, t1, 0xEE);
    const __m256 r2 = _mm256_shuffle_ps(t2, t3, 0x44);
    const __m256 r3 = _mm256_shuffle_ps(t2, t3, 0xEE);
    _mm_store_ps(&x[i[0]].x, _mm256_castps256_ps128(r0));
    _mm_store_ps(&x[i[1]].x, _mm256_castps256_ps128(r1));
    _mm_store_ps(&x[i[2]].x, _mm256_castps256_ps128(r2));
    _mm_store_ps(&x[i[3]].x, _mm256_castps256_ps128(r3));
    _mm_store_ps(&x[i[4]].x, _mm256_extractf128_ps(r0, 1));
    _mm_store_ps(&x[i[5]].x, _mm256_extractf128_ps(r1, 1));
    _mm_store_ps(&x[i[6]].x, _mm256_extractf128_ps(r2, 1));
    _mm_store_ps(&x[i[7]].x, _mm256_extractf128_ps(r3, 1));
}

using simd::add;
using simd::mul;
using simd::sub;

// u·u + v·v + s·s, summed left to right as the scalar kernels do.
PLIANT_AVX2_INLINE __m256 norm2(__m256 u, __m256 v, __m256 s) {
    return add(add(mul(u, u), mul(v, v)), mul(s, s));
}

// The projection of 8 edges whose vertices a, b are loaded; updates them in place.
PLIANT_AVX2_INLINE void project_edges8(Lanes8& a, Lanes8& b, const float* rest_lengths,
                                       __m256 inv_k8, __m256 alpha8) {
    const __m256 zero = _mm256_setzero_ps();
    const __m256 w = add(a.w, b.w);
    const __m256 dx = sub(a.x, b.x);
    const __m256 dy = sub(a.y, b.y);
    const __m256 dz = sub(a.z, b.z);
    const __m256 length = _mm256_sqrt_ps(norm2(dx, dy, dz));
    const __m256 valid =
        _mm256_and_ps(_mm256_cmp_ps(w, zero, _CMP_GT_OQ), _mm256_cmp_ps(length, zero, _CMP_GT_OQ));
    const __m256 denominator = add(mul(w, inv_k8), alpha8);
    const __m256 violation = sub(length, _mm256_loadu_ps(rest_lengths));
    const __m256 s =
        _mm256_and_ps(valid, _mm256_div_ps(sub(zero, violation), mul(denominator, length)));
    const __m256 sa = mul(a.w, s);
    const __m256 sb = mul(b.w, s);
    a.x = add(a.x, mul(sa, dx));
    a.y = add(a.y, mul(sa, dy));
    a.z = add(a.z, mul(sa, dz));
    b.x = sub(b.x, mul(sb, dx));
    b.y = sub(b.y, mul(sb, dy));
    b.z = sub(b.z, mul(sb, dz));
}

}  // namespace

PLIANT_AVX2_FN std::int64_t project_edges_avx2(Float4* x, const std::array<std::int32_t, 2>* e,
                                               const float* rest_lengths, std::int64_t count,
                                               float inv_k, float alpha) {
    const __m256 inv_k8 = _mm256_set1_ps(inv_k);
    const __m256 alpha8 = _mm256_set1_ps(alpha);
    std::int64_t k = 0;
    for (; k + 8 <= count; k += 8) {
        std::int32_t ia[8];
        std::int32_t ib[8];
        for (int l = 0; l < 8; ++l) {
            ia[l] = e[k + l][0];
            ib[l] = e[k + l][1];
        }
        Lanes8 a = load8(x, ia);
        Lanes8 b = load8(x, ib);
        project_edges8(a, b, rest_lengths + k, inv_k8, alpha8);
        store8(x, ia, a);
        store8(x, ib, b);
    }
    return k;
}

namespace {

// The projection of 8 tets whose vertices p0..p3 are loaded (project_tet's arithmetic,
// tet_gradient6; alpha8 = 36 α); updates their positions in place and returns the mask of the
// tets at risk (bit l: lane l).
PLIANT_AVX2_INLINE int project_tets8(Lanes8& p0, Lanes8& p1, Lanes8& p2, Lanes8& p3,
                                     const float* rest_volumes, __m256 inv_k8, __m256 alpha8) {
    const __m256 zero = _mm256_setzero_ps();
    const __m256 e1x = sub(p1.x, p0.x), e1y = sub(p1.y, p0.y), e1z = sub(p1.z, p0.z);
    const __m256 e2x = sub(p2.x, p0.x), e2y = sub(p2.y, p0.y), e2z = sub(p2.z, p0.z);
    const __m256 e3x = sub(p3.x, p0.x), e3y = sub(p3.y, p0.y), e3z = sub(p3.z, p0.z);
    const __m256 g1x = sub(mul(e2y, e3z), mul(e2z, e3y));
    const __m256 g1y = sub(mul(e2z, e3x), mul(e2x, e3z));
    const __m256 g1z = sub(mul(e2x, e3y), mul(e2y, e3x));
    const __m256 g2x = sub(mul(e3y, e1z), mul(e3z, e1y));
    const __m256 g2y = sub(mul(e3z, e1x), mul(e3x, e1z));
    const __m256 g2z = sub(mul(e3x, e1y), mul(e3y, e1x));
    const __m256 g3x = sub(mul(e1y, e2z), mul(e1z, e2y));
    const __m256 g3y = sub(mul(e1z, e2x), mul(e1x, e2z));
    const __m256 g3z = sub(mul(e1x, e2y), mul(e1y, e2x));
    const __m256 g0x = sub(zero, add(add(g1x, g2x), g3x));
    const __m256 g0y = sub(zero, add(add(g1y, g2y), g3y));
    const __m256 g0z = sub(zero, add(add(g1z, g2z), g3z));
    const __m256 volume = add(add(mul(e1x, g1x), mul(e1y, g1y)), mul(e1z, g1z));
    const __m256 weight =
        add(add(add(mul(p0.w, norm2(g0x, g0y, g0z)), mul(p1.w, norm2(g1x, g1y, g1z))),
                mul(p2.w, norm2(g2x, g2y, g2z))),
            mul(p3.w, norm2(g3x, g3y, g3z)));
    const __m256 rest = mul(_mm256_loadu_ps(rest_volumes), _mm256_set1_ps(6.0f));
    const int at_risk = _mm256_movemask_ps(
        _mm256_cmp_ps(volume, mul(rest, _mm256_set1_ps(AT_RISK_RATIO)), _CMP_LT_OQ));
    const __m256 valid = _mm256_cmp_ps(weight, zero, _CMP_GT_OQ);
    const __m256 denominator = add(mul(weight, inv_k8), alpha8);
    const __m256 violation = sub(volume, rest);
    const __m256 dlambda = _mm256_and_ps(valid, _mm256_div_ps(sub(zero, violation), denominator));
    const __m256 s0 = mul(p0.w, dlambda);
    const __m256 s1 = mul(p1.w, dlambda);
    const __m256 s2 = mul(p2.w, dlambda);
    const __m256 s3 = mul(p3.w, dlambda);
    p0.x = add(p0.x, mul(s0, g0x)), p0.y = add(p0.y, mul(s0, g0y));
    p0.z = add(p0.z, mul(s0, g0z));
    p1.x = add(p1.x, mul(s1, g1x)), p1.y = add(p1.y, mul(s1, g1y));
    p1.z = add(p1.z, mul(s1, g1z));
    p2.x = add(p2.x, mul(s2, g2x)), p2.y = add(p2.y, mul(s2, g2y));
    p2.z = add(p2.z, mul(s2, g2z));
    p3.x = add(p3.x, mul(s3, g3x)), p3.y = add(p3.y, mul(s3, g3y));
    p3.z = add(p3.z, mul(s3, g3z));
    return at_risk;
}

// Flags the lanes of `mask` in at_risk[0..8) (rare: tets near inversion).
inline void flag_at_risk(int mask, std::uint8_t* at_risk, std::int64_t& num_at_risk) {
    if (mask != 0) {
        for (int l = 0; l < 8; ++l) {
            if ((mask >> l & 1) != 0) {
                at_risk[l] = 1;
                ++num_at_risk;
            }
        }
    }
}

}  // namespace

PLIANT_AVX2_FN std::int64_t project_tets_avx2(Float4* x, const geometry::Tet* t,
                                              const float* rest_volumes, std::uint8_t* at_risk,
                                              std::int64_t count, float inv_k, float alpha,
                                              std::int64_t& num_at_risk) {
    const __m256 inv_k8 = _mm256_set1_ps(inv_k);
    const __m256 alpha8 = _mm256_set1_ps(tet_alpha36(alpha));
    std::int64_t flagged = 0;  // a local: the stores below may alias num_at_risk
    std::int64_t k = 0;
    for (; k + 8 <= count; k += 8) {
        std::int32_t i[4][8];
        for (int l = 0; l < 8; ++l) {
            for (int m = 0; m < 4; ++m) {
                i[m][l] = t[k + l][static_cast<std::size_t>(m)];
            }
        }
        Lanes8 p0 = load8(x, i[0]);
        Lanes8 p1 = load8(x, i[1]);
        Lanes8 p2 = load8(x, i[2]);
        Lanes8 p3 = load8(x, i[3]);
        flag_at_risk(project_tets8(p0, p1, p2, p3, rest_volumes + k, inv_k8, alpha8), at_risk + k,
                     flagged);
        store8(x, i[0], p0);
        store8(x, i[1], p1);
        store8(x, i[2], p2);
        store8(x, i[3], p3);
    }
    num_at_risk += flagged;
    return k;
}

namespace {

// The lanes l < n of 8 (n ≤ 8) as a mask for _mm256_maskload_ps / _mm256_maskstore_ps.
PLIANT_AVX2_INLINE __m256i lane_mask(std::int64_t n) {
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(n)), lanes);
}

// Vertices i .. i + 8 of p (every lane; masked lanes read 0).
PLIANT_AVX2_INLINE Lanes8 load_soa(const SoaPositions& p, std::int64_t i) {
    return {_mm256_loadu_ps(p.x + i), _mm256_loadu_ps(p.y + i), _mm256_loadu_ps(p.z + i),
            _mm256_loadu_ps(p.w + i)};
}
PLIANT_AVX2_INLINE Lanes8 load_soa(const SoaPositions& p, std::int64_t i, __m256i mask) {
    return {_mm256_maskload_ps(p.x + i, mask), _mm256_maskload_ps(p.y + i, mask),
            _mm256_maskload_ps(p.z + i, mask), _mm256_maskload_ps(p.w + i, mask)};
}
// Positions only: w does not change.
PLIANT_AVX2_INLINE void store_soa(const SoaPositions& p, std::int64_t i, const Lanes8& l) {
    _mm256_storeu_ps(p.x + i, l.x);
    _mm256_storeu_ps(p.y + i, l.y);
    _mm256_storeu_ps(p.z + i, l.z);
}
PLIANT_AVX2_INLINE void store_soa(const SoaPositions& p, std::int64_t i, const Lanes8& l,
                                  __m256i mask) {
    _mm256_maskstore_ps(p.x + i, mask, l.x);
    _mm256_maskstore_ps(p.y + i, mask, l.y);
    _mm256_maskstore_ps(p.z + i, mask, l.z);
}

// A run of edges: edge q ∈ [0, count) joins a + q and b + q.
PLIANT_AVX2_INLINE void edge_run_soa(const SoaPositions& p, std::int64_t a, std::int64_t b,
                                     const float* rest_lengths, std::int64_t count, __m256 inv_k8,
                                     __m256 alpha8) {
    std::int64_t k = 0;
    for (; k + 8 <= count; k += 8) {
        Lanes8 la = load_soa(p, a + k);
        Lanes8 lb = load_soa(p, b + k);
        project_edges8(la, lb, rest_lengths + k, inv_k8, alpha8);
        store_soa(p, a + k, la);
        store_soa(p, b + k, lb);
    }
    if (k < count) {
        // Masked lanes: w = 0, so their edges are invalid (s = 0) and not stored.
        const __m256i mask = lane_mask(count - k);
        float lengths[8];
        _mm256_storeu_ps(lengths, _mm256_maskload_ps(rest_lengths + k, mask));
        Lanes8 la = load_soa(p, a + k, mask);
        Lanes8 lb = load_soa(p, b + k, mask);
        project_edges8(la, lb, lengths, inv_k8, alpha8);
        store_soa(p, a + k, la, mask);
        store_soa(p, b + k, lb, mask);
    }
}

// A run of tets: tet q ∈ [0, count) has vertices first[m] + q.
PLIANT_AVX2_INLINE void tet_run_soa(const SoaPositions& p, const std::array<std::int64_t, 4>& first,
                                    const float* rest_volumes, std::uint8_t* at_risk,
                                    std::int64_t count, __m256 inv_k8, __m256 alpha8,
                                    std::int64_t& flagged) {
    std::int64_t k = 0;
    for (; k + 8 <= count; k += 8) {
        Lanes8 p0 = load_soa(p, first[0] + k);
        Lanes8 p1 = load_soa(p, first[1] + k);
        Lanes8 p2 = load_soa(p, first[2] + k);
        Lanes8 p3 = load_soa(p, first[3] + k);
        flag_at_risk(project_tets8(p0, p1, p2, p3, rest_volumes + k, inv_k8, alpha8), at_risk + k,
                     flagged);
        store_soa(p, first[0] + k, p0);
        store_soa(p, first[1] + k, p1);
        store_soa(p, first[2] + k, p2);
        store_soa(p, first[3] + k, p3);
    }
    if (k < count) {
        // Masked lanes: w = 0 and V0 = 0, so they move nothing and are not at risk (0 < 0 is
        // false); the mask drops them anyway.
        const std::int64_t n = count - k;
        const __m256i mask = lane_mask(n);
        float volumes[8];
        _mm256_storeu_ps(volumes, _mm256_maskload_ps(rest_volumes + k, mask));
        Lanes8 p0 = load_soa(p, first[0] + k, mask);
        Lanes8 p1 = load_soa(p, first[1] + k, mask);
        Lanes8 p2 = load_soa(p, first[2] + k, mask);
        Lanes8 p3 = load_soa(p, first[3] + k, mask);
        const int risk = project_tets8(p0, p1, p2, p3, volumes, inv_k8, alpha8) &
                         ((1 << static_cast<int>(n)) - 1);
        flag_at_risk(risk, at_risk + k, flagged);
        store_soa(p, first[0] + k, p0, mask);
        store_soa(p, first[1] + k, p1, mask);
        store_soa(p, first[2] + k, p2, mask);
        store_soa(p, first[3] + k, p3, mask);
    }
}

// The pieces of the runs covering constraints [b, e) of a colour (indices within it), in order:
// constraints q .. q + n of run `run`, from its (o)th. Plain code (no intrinsics), so the AVX2
// functions below inline it in every build (a lambda inside them would lack their target).
struct RunPiece {
    std::int64_t q = 0, n = 0, o = 0;
    const LatticeRun* run = nullptr;
};
class RunPieces {
public:
    RunPieces(const LatticeRuns& runs, std::int64_t b, std::int64_t e)
        : m_runs(runs),
          m_q(b),
          m_e(e),
          // The run holding constraint b (its begin is the last ≤ begin + b).
          m_r(std::upper_bound(runs.run_begins, runs.run_begins + runs.num_runs, runs.begin + b) -
              runs.run_begins - 1) {}
    bool next(RunPiece& piece) {
        if (m_q >= m_e) {
            return false;
        }
        const std::int64_t run_end =
            m_r + 1 < m_runs.num_runs ? m_runs.run_begins[m_r + 1] - m_runs.begin : m_runs.count;
        piece.q = m_q;
        piece.n = std::min(m_e, run_end) - m_q;
        piece.run = &m_runs.runs[m_r];
        piece.o = m_runs.begin + m_q - m_runs.runs[m_r].begin;
        m_q += piece.n;
        ++m_r;
        return true;
    }

private:
    const LatticeRuns& m_runs;
    std::int64_t m_q, m_e, m_r;
};

}  // namespace

PLIANT_AVX2_FN void project_edge_runs_soa_avx2(const SoaPositions& p, const LatticeRuns& runs,
                                               std::int64_t b, std::int64_t e,
                                               const float* rest_lengths, float inv_k,
                                               float alpha) {
    const __m256 inv_k8 = _mm256_set1_ps(inv_k);
    const __m256 alpha8 = _mm256_set1_ps(alpha);
    RunPieces pieces(runs, b, e);
    for (RunPiece c; pieces.next(c);) {
        edge_run_soa(p, c.run->first[0] + c.o, c.run->first[1] + c.o, rest_lengths + c.q, c.n,
                     inv_k8, alpha8);
    }
}

PLIANT_AVX2_FN void project_tet_runs_soa_avx2(const SoaPositions& p, const LatticeRuns& runs,
                                              std::int64_t b, std::int64_t e,
                                              const float* rest_volumes, std::uint8_t* at_risk,
                                              float inv_k, float alpha, std::int64_t& num_at_risk) {
    const __m256 inv_k8 = _mm256_set1_ps(inv_k);
    const __m256 alpha8 = _mm256_set1_ps(tet_alpha36(alpha));
    std::int64_t flagged = 0;  // a local: the stores may alias num_at_risk
    RunPieces pieces(runs, b, e);
    for (RunPiece c; pieces.next(c);) {
        const std::array<std::int64_t, 4> first{c.run->first[0] + c.o, c.run->first[1] + c.o,
                                                c.run->first[2] + c.o, c.run->first[3] + c.o};
        tet_run_soa(p, first, rest_volumes + c.q, at_risk + c.q, c.n, inv_k8, alpha8, flagged);
    }
    num_at_risk += flagged;
}

#else  // no AVX2 on this target
std::int64_t project_edges_avx2(Float4*, const std::array<std::int32_t, 2>*, const float*,
                                std::int64_t, float, float) {
    return 0;
}
std::int64_t project_tets_avx2(Float4*, const geometry::Tet*, const float*, std::uint8_t*,
                               std::int64_t, float, float, std::int64_t&) {
    return 0;
}
void project_edge_runs_soa_avx2(const SoaPositions&, const LatticeRuns&, std::int64_t, std::int64_t,
                                const float*, float, float) {}
void project_tet_runs_soa_avx2(const SoaPositions&, const LatticeRuns&, std::int64_t, std::int64_t,
                               const float*, std::uint8_t*, float, float, std::int64_t&) {}

#endif

}  // namespace pliant::pbd::detail
