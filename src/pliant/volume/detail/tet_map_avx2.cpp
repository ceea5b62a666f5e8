#include "pliant/volume/detail/tet_map_avx2.hpp"

#include "pliant/core/simd_dispatch.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>
#endif

namespace pliant::volume::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

// std::min(a, b) = (b < a) ? b : a, and std::max(a, b) = (a < b) ? b : a, with their NaN cases.
PLIANT_AVX2_INLINE __m256d std_min(__m256d a, __m256d b) {
    return _mm256_min_pd(b, a);
}
PLIANT_AVX2_INLINE __m256d std_max(__m256d a, __m256d b) {
    return _mm256_max_pd(b, a);
}

// Tets [4h, 4h + 4) of the batch: the bits of `boxes` and `inside` for them (bit 0: tet 4h).
PLIANT_AVX2_INLINE void half(const double p[4][3][TET_BATCH], const double rows[3][3][TET_BATCH],
                             const double det[TET_BATCH], double b, double inv_b,
                             const std::int64_t nodes[3], int h, BoxFirst& out, int& boxes,
                             int& inside) {
    const int o = 4 * h;
    const __m256d zero = _mm256_setzero_pd();
    const __m256d abs_det = _mm256_andnot_pd(_mm256_set1_pd(-0.0), _mm256_loadu_pd(det + o));
    // |det| > 0 and finite (NaN: false in both).
    __m256d ok = _mm256_and_pd(_mm256_cmp_pd(abs_det, zero, _CMP_GT_OQ),
                               _mm256_cmp_pd(abs_det, _mm256_set1_pd(__builtin_inf()), _CMP_LT_OQ));
    const __m256d vb = _mm256_set1_pd(b);
    const __m256d vinv = _mm256_set1_pd(inv_b);
    __m256d lo[3];
    for (int a = 0; a < 3; ++a) {
        // std::min({p0, p1, p2, p3}): min_element keeps the first of equal values.
        const __m256d p0 = _mm256_loadu_pd(p[0][a] + o);
        const __m256d p1 = _mm256_loadu_pd(p[1][a] + o);
        const __m256d p2 = _mm256_loadu_pd(p[2][a] + o);
        const __m256d p3 = _mm256_loadu_pd(p[3][a] + o);
        const __m256d mn = std_min(std_min(std_min(p0, p1), p2), p3);
        const __m256d mx = std_max(std_max(std_max(p0, p1), p2), p3);
        const __m256d lo_nodes = inv_b > 0.0 ? _mm256_mul_pd(mn, vinv) : _mm256_div_pd(mn, vb);
        const __m256d hi_nodes = inv_b > 0.0 ? _mm256_mul_pd(mx, vinv) : _mm256_div_pd(mx, vb);
        const __m256d last = _mm256_set1_pd(static_cast<double>(nodes[a] - 1));
        // std::max(0.0, ceil), std::min(nodes − 1, floor); the box is empty when lo > hi (for
        // boxes that are not, both are integers in [0, nodes − 1]).
        lo[a] = std_max(zero, _mm256_round_pd(lo_nodes, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC));
        const __m256d hi =
            std_min(last, _mm256_round_pd(hi_nodes, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC));
        ok = _mm256_and_pd(ok, _mm256_cmp_pd(lo[a], hi, _CMP_LE_OQ));
        const __m128i lo32 = _mm256_cvttpd_epi32(lo[a]);
        const __m128i hi32 = _mm256_cvttpd_epi32(hi);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out.lo[a] + o), lo32);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out.hi[a] + o), hi32);
    }
    // The first node x = B · lo: λk = rows[k] · (x − p3), dot() in its order.
    __m256d d[3];
    for (int a = 0; a < 3; ++a) {
        d[a] = _mm256_sub_pd(_mm256_mul_pd(lo[a], vb), _mm256_loadu_pd(p[3][a] + o));
    }
    __m256d l[3];
    for (int k = 0; k < 3; ++k) {
        const __m256d xx = _mm256_mul_pd(_mm256_loadu_pd(rows[k][0] + o), d[0]);
        const __m256d yy = _mm256_mul_pd(_mm256_loadu_pd(rows[k][1] + o), d[1]);
        const __m256d zz = _mm256_mul_pd(_mm256_loadu_pd(rows[k][2] + o), d[2]);
        l[k] = _mm256_add_pd(_mm256_add_pd(xx, yy), zz);
        _mm256_storeu_pd(out.l[k] + o, l[k]);
    }
    const __m256d l3 =
        _mm256_sub_pd(_mm256_sub_pd(_mm256_sub_pd(_mm256_set1_pd(1.0), l[0]), l[1]), l[2]);
    const __m256d s = std_min(std_min(std_min(l[0], l[1]), l[2]), l3);
    const __m256d in = _mm256_and_pd(ok, _mm256_cmp_pd(s, _mm256_set1_pd(-1e-9), _CMP_GE_OQ));
    boxes |= _mm256_movemask_pd(ok) << o;
    inside |= _mm256_movemask_pd(in) << o;
}

}  // namespace

PLIANT_AVX2_FN bool box_first_avx2(const double p[4][3][TET_BATCH],
                                   const double rows[3][3][TET_BATCH], const double det[TET_BATCH],
                                   double b, double inv_b, const std::int64_t nodes[3],
                                   BoxFirst& out) {
    int boxes = 0;
    int inside = 0;
    half(p, rows, det, b, inv_b, nodes, 0, out, boxes, inside);
    half(p, rows, det, b, inv_b, nodes, 1, out, boxes, inside);
    out.boxes = boxes;
    out.inside = inside;
    return true;
}

#else  // no AVX2 on this target
bool box_first_avx2(const double (*)[3][TET_BATCH], const double (*)[3][TET_BATCH], const double*,
                    double, double, const std::int64_t*, BoxFirst&) {
    return false;
}
#endif

}  // namespace pliant::volume::detail
