#include "pliant/volume/detail/resample_avx2.hpp"

#include <algorithm>
#include <atomic>
#include <limits>

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define PLIANT_VOLUME_AVX2 1
// "avx2" only, not "fma": the compiler must not contract a · b + c, which would round differently
// from the scalar kernels.
#define PLIANT_AVX2_FN __attribute__((target("avx2")))
#define PLIANT_AVX2_INLINE inline __attribute__((target("avx2"), always_inline))
#endif

namespace pliant::volume::detail {

namespace {
std::atomic<bool> g_avx2_allowed{true};
}  // namespace

void allow_avx2(bool allowed) {
    g_avx2_allowed.store(allowed, std::memory_order_relaxed);
}

#if defined(PLIANT_VOLUME_AVX2)

bool has_avx2() {
    static const bool cpu_has = __builtin_cpu_supports("avx2") != 0;
    return cpu_has && g_avx2_allowed.load(std::memory_order_relaxed);
}

namespace {

// The low 32 bits of each 64-bit lane of m (a compare mask of 4 doubles) as a 4 × 32-bit mask.
PLIANT_AVX2_INLINE __m128 narrow_mask(__m256d m) {
    const __m128 lo = _mm_castpd_ps(_mm256_castpd256_pd128(m));
    const __m128 hi = _mm_castpd_ps(_mm256_extractf128_pd(m, 1));
    return _mm_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));
}

// u + f·(v − u), the lerp of sample_trilinear.
PLIANT_AVX2_INLINE __m128 lerp(__m128 u, __m128 v, __m128 f) {
    return _mm_add_ps(u, _mm_mul_ps(f, _mm_sub_ps(v, u)));
}

// One axis of 4 coordinates: the lower voxel index (clamped as sample_trilinear clamps) and the
// fraction, as float.
struct Axis {
    __m128i index;
    __m128 fraction;
};
PLIANT_AVX2_INLINE Axis axis(__m256d g, __m256d top) {
    // std::clamp(g, 0, n − 1); max_pd returns its second operand for NaN (masked out later).
    const __m256d c = _mm256_min_pd(_mm256_max_pd(g, _mm256_setzero_pd()), top);
    const __m128i i = _mm256_cvttpd_epi32(c);
    return {i, _mm256_cvtpd_ps(_mm256_sub_pd(c, _mm256_cvtepi32_pd(i)))};
}

PLIANT_AVX2_INLINE double min4(__m256d v) {
    const __m128d m = _mm_min_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    return _mm_cvtsd_f64(_mm_min_sd(m, _mm_unpackhi_pd(m, m)));
}
PLIANT_AVX2_INLINE double max4(__m256d v) {
    const __m128d m = _mm_max_pd(_mm256_castpd256_pd128(v), _mm256_extractf128_pd(v, 1));
    return _mm_cvtsd_f64(_mm_max_sd(m, _mm_unpackhi_pd(m, m)));
}

// slice_rows() with the edges 4 at a time (the 8 entries of the edge arrays, 2 of them padding).
PLIANT_AVX2_INLINE void slice_rows4(const TetRaster& t, std::int64_t k, std::int64_t& j_begin,
                                    std::int64_t& j_end) {
    const __m256d z = _mm256_set1_pd(static_cast<double>(k));
    const __m256d grow = _mm256_set1_pd(1e-6);
    const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    const __m256d neg_inf = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
    __m256d y_min = inf;
    __m256d y_max = neg_inf;
    for (int h = 0; h < 8; h += 4) {
        const __m256d z_lo = _mm256_loadu_pd(t.edge_z_lo + h);
        const __m256d z_hi = _mm256_loadu_pd(t.edge_z_hi + h);
        const __m256d is_crossed =
            _mm256_and_pd(_mm256_cmp_pd(z, _mm256_sub_pd(z_lo, grow), _CMP_GE_OQ),
                          _mm256_cmp_pd(z, _mm256_add_pd(z_hi, grow), _CMP_LE_OQ));
        const __m256d zc = _mm256_min_pd(_mm256_max_pd(z, z_lo), z_hi);
        const __m256d y =
            _mm256_add_pd(_mm256_loadu_pd(t.edge_y0 + h),
                          _mm256_mul_pd(_mm256_sub_pd(zc, _mm256_loadu_pd(t.edge_z0 + h)),
                                        _mm256_loadu_pd(t.edge_slope + h)));
        y_min = _mm256_min_pd(y_min, _mm256_blendv_pd(inf, y, is_crossed));
        y_max = _mm256_max_pd(y_max, _mm256_blendv_pd(neg_inf, y, is_crossed));
    }
    rows_of_extent(t, min4(y_min), max4(y_max), j_begin, j_end);
}

// lo[l] = src[at[l] + offset], hi[l] = src[at[l] + offset + 1] for the 4 lanes l.
PLIANT_AVX2_INLINE void pairs(const float* src, const std::int32_t at[4], std::int32_t offset,
                              __m128& lo, __m128& hi) {
    const auto* p0 = reinterpret_cast<const __m64*>(src + at[0] + offset);
    const auto* p1 = reinterpret_cast<const __m64*>(src + at[1] + offset);
    const auto* p2 = reinterpret_cast<const __m64*>(src + at[2] + offset);
    const auto* p3 = reinterpret_cast<const __m64*>(src + at[3] + offset);
    const __m128 l01 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), p0), p1);  // a0 b0 a1 b1
    const __m128 l23 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), p2), p3);  // a2 b2 a3 b3
    lo = _mm_shuffle_ps(l01, l23, _MM_SHUFFLE(2, 0, 2, 0));
    hi = _mm_shuffle_ps(l01, l23, _MM_SHUFFLE(3, 1, 3, 1));
}

template <bool INTERIOR>
PLIANT_AVX2_INLINE int sample_f32(const float* src, const std::int64_t n[3], const SpanBatch& batch,
                                  float scale, float* dst) {
    const int count = batch.num_voxels & ~3;
    const __m256d top_x = _mm256_set1_pd(static_cast<double>(n[0] - 1));
    const __m256d top_y = _mm256_set1_pd(static_cast<double>(n[1] - 1));
    const __m256d top_z = _mm256_set1_pd(static_cast<double>(n[2] - 1));
    const __m256d half = _mm256_set1_pd(-0.5);
    const __m256d end_x = _mm256_set1_pd(static_cast<double>(n[0]) - 0.5);
    const __m256d end_y = _mm256_set1_pd(static_cast<double>(n[1]) - 0.5);
    const __m256d end_z = _mm256_set1_pd(static_cast<double>(n[2]) - 0.5);
    const auto nx = static_cast<std::int32_t>(n[0]);
    const auto nxy = static_cast<std::int32_t>(n[0] * n[1]);
    const __m128i nx4 = _mm_set1_epi32(nx);
    const __m128i nxy4 = _mm_set1_epi32(nxy);
    const __m128i last_x = _mm_set1_epi32(static_cast<std::int32_t>(n[0] - 1));
    const __m128i last_y = _mm_set1_epi32(static_cast<std::int32_t>(n[1] - 1));
    const __m128i last_z = _mm_set1_epi32(static_cast<std::int32_t>(n[2] - 1));
    const __m128i one = _mm_set1_epi32(1);
    const __m128 scale4 = _mm_set1_ps(scale);
    for (int e = 0; e < count; e += 4) {
        const __m256d gx = _mm256_load_pd(batch.g[0] + e);
        const __m256d gy = _mm256_load_pd(batch.g[1] + e);
        const __m256d gz = _mm256_load_pd(batch.g[2] + e);
        const Axis ax = axis(gx, top_x);
        const Axis ay = axis(gy, top_y);
        const Axis az = axis(gz, top_z);
        // Offsets to the upper neighbours: 0 on the last voxel of an axis (clamped samples).
        __m128i ox = one;
        __m128i oy = nx4;
        __m128i oz = nxy4;
        if constexpr (!INTERIOR) {
            ox = _mm_and_si128(_mm_cmpgt_epi32(last_x, ax.index), one);
            oy = _mm_and_si128(_mm_cmpgt_epi32(last_y, ay.index), nx4);
            oz = _mm_and_si128(_mm_cmpgt_epi32(last_z, az.index), nxy4);
        }
        const __m128i p = _mm_add_epi32(
            ax.index,
            _mm_mullo_epi32(
                nx4, _mm_add_epi32(ay.index,
                                   _mm_mullo_epi32(_mm_set1_epi32(static_cast<std::int32_t>(n[1])),
                                                   az.index))));
        __m128 v000, v100, v010, v110, v001, v101, v011, v111;
        if constexpr (INTERIOR) {
            // The x neighbours are adjacent: one 8-byte load per pair (gathers are slow on some
            // CPUs, e.g. Zen 4).
            alignas(16) std::int32_t at[4];
            _mm_store_si128(reinterpret_cast<__m128i*>(at), p);
            pairs(src, at, 0, v000, v100);
            pairs(src, at, nx, v010, v110);
            pairs(src, at, nxy, v001, v101);
            pairs(src, at, nx + nxy, v011, v111);
        } else {
            const __m128i pz = _mm_add_epi32(p, oz);
            v000 = _mm_i32gather_ps(src, p, 4);
            v100 = _mm_i32gather_ps(src, _mm_add_epi32(p, ox), 4);
            v010 = _mm_i32gather_ps(src, _mm_add_epi32(p, oy), 4);
            v110 = _mm_i32gather_ps(src, _mm_add_epi32(_mm_add_epi32(p, oy), ox), 4);
            v001 = _mm_i32gather_ps(src, pz, 4);
            v101 = _mm_i32gather_ps(src, _mm_add_epi32(pz, ox), 4);
            v011 = _mm_i32gather_ps(src, _mm_add_epi32(pz, oy), 4);
            v111 = _mm_i32gather_ps(src, _mm_add_epi32(_mm_add_epi32(pz, oy), ox), 4);
        }
        const __m128 v00 = lerp(v000, v100, ax.fraction);
        const __m128 v10 = lerp(v010, v110, ax.fraction);
        const __m128 v01 = lerp(v001, v101, ax.fraction);
        const __m128 v11 = lerp(v011, v111, ax.fraction);
        const __m128 v0 = lerp(v00, v10, ay.fraction);
        const __m128 v1 = lerp(v01, v11, ay.fraction);
        __m128 v = lerp(v0, v1, az.fraction);
        if constexpr (!INTERIOR) {
            // 0 outside [−0.5, n − 0.5] on any axis (NaN too: ordered compares).
            const __m256d in =
                _mm256_and_pd(_mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(gx, half, _CMP_GE_OQ),
                                                          _mm256_cmp_pd(gx, end_x, _CMP_LE_OQ)),
                                            _mm256_and_pd(_mm256_cmp_pd(gy, half, _CMP_GE_OQ),
                                                          _mm256_cmp_pd(gy, end_y, _CMP_LE_OQ))),
                              _mm256_and_pd(_mm256_cmp_pd(gz, half, _CMP_GE_OQ),
                                            _mm256_cmp_pd(gz, end_z, _CMP_LE_OQ)));
            v = _mm_and_ps(v, narrow_mask(in));
        }
        // convert_sample<float>: v · scale.
        v = _mm_mul_ps(v, scale4);
        alignas(16) float out[4];
        _mm_store_ps(out, v);
        dst[batch.index[e]] = out[0];
        dst[batch.index[e + 1]] = out[1];
        dst[batch.index[e + 2]] = out[2];
        dst[batch.index[e + 3]] = out[3];
    }
    return count;
}

}  // namespace

PLIANT_AVX2_FN std::int64_t append_layers_avx2(const TetRaster& t, std::int64_t k,
                                               std::int64_t k_end, std::int64_t nx,
                                               std::int64_t nxy, SpanBatch& batch,
                                               std::int64_t& num_voxels) {
    constexpr double TOL = 1e-6;
    const __m256d lane = _mm256_setr_pd(0.0, 1.0, 2.0, 3.0);
    const __m256i lane64 = _mm256_setr_epi64x(0, 1, 2, 3);
    const __m256d four = _mm256_set1_pd(4.0);
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d tol = _mm256_set1_pd(TOL);
    // row_span_fast()'s bounds: the box ± ½ voxel, kept within a voxel of it.
    const double r_lo = static_cast<double>(t.lo[0]) - 0.5;
    const double r_hi = static_cast<double>(t.hi[0]) + 0.5;
    const __m256d x_lo0 = _mm256_set1_pd(r_lo);
    const __m256d x_hi0 = _mm256_set1_pd(r_hi);
    const __m256d lo_cap = _mm256_set1_pd(r_hi + 1.0);
    const __m256d hi_floor = _mm256_set1_pd(r_lo - 1.0);
    const __m256d box_lo = _mm256_set1_pd(static_cast<double>(t.lo[0]));
    const __m256d box_hi = _mm256_set1_pd(static_cast<double>(t.hi[0]));
    __m256d plane_j[4];
    __m256d neg_inv_a[4];
    __m256d cap[4];
    __m256d root_floor[4];
    for (int q = 0; q < 4; ++q) {
        plane_j[q] = _mm256_set1_pd(t.plane[q][1]);
        neg_inv_a[q] = _mm256_set1_pd(t.neg_inv_a[q]);
        cap[q] = _mm256_set1_pd(t.root_cap[q]);
        root_floor[q] = _mm256_set1_pd(t.root_floor[q]);
    }
    __m256d map_i[3];
    __m256d map_j[3];
    for (int a = 0; a < 3; ++a) {
        map_i[a] = _mm256_set1_pd(t.map[a][0]);
        map_j[a] = _mm256_set1_pd(t.map[a][1]);
    }
    const std::int64_t k0 = std::max(t.k_lo, k);
    const std::int64_t k1 = std::min(t.k_hi + 1, k_end);
    batch.is_interior = batch.is_interior && t.is_interior;
    for (k = k0; k < k1; ++k) {
        std::int64_t j0 = 0;
        std::int64_t j1 = 0;
        slice_rows4(t, k, j0, j1);
        if (t.flat_faces != 0) {
            flat_rows(t, k, j0, j1);
        }
        // Each row writes at most 8 entries (the tet is at most 8 voxels wide).
        if (batch.num_voxels + (j1 - j0) * 8 > SpanBatch::CAPACITY) {
            return k;
        }
        const double kd = static_cast<double>(k);
        __m256d gamma[4];
        for (int q = 0; q < 4; ++q) {
            gamma[q] = _mm256_set1_pd(t.plane[q][2] * kd + t.plane[q][3]);
        }
        __m256d g_k[3];
        for (int a = 0; a < 3; ++a) {
            g_k[a] = _mm256_set1_pd(t.map[a][3] + t.map[a][2] * kd);
        }
        const std::int64_t layer_base = k * nxy;
        for (std::int64_t j = j0; j < j1; j += 4) {
            // Rows j … j + 3 in the lanes: row_span_fast() lane by lane.
            const __m256d jd = _mm256_add_pd(_mm256_set1_pd(static_cast<double>(j)), lane);
            __m256d x_lo = x_lo0;
            __m256d x_hi = x_hi0;
            for (int q = 0; q < 4; ++q) {
                const __m256d beta = _mm256_add_pd(_mm256_mul_pd(plane_j[q], jd), gamma[q]);
                const __m256d root = _mm256_mul_pd(beta, neg_inv_a[q]);
                x_lo = _mm256_max_pd(x_lo, _mm256_min_pd(root, cap[q]));
                x_hi = _mm256_min_pd(x_hi, _mm256_max_pd(root, root_floor[q]));
            }
            x_lo = _mm256_min_pd(x_lo, lo_cap);
            x_hi = _mm256_max_pd(x_hi, hi_floor);
            __m256d b = _mm256_ceil_pd(_mm256_sub_pd(x_lo, tol));
            __m256d e = _mm256_floor_pd(_mm256_add_pd(x_hi, tol));
            const int rows = static_cast<int>(std::min<std::int64_t>(4, j1 - j));
            const __m256d is_near =
                _mm256_or_pd(_mm256_cmp_pd(b, _mm256_add_pd(x_lo, tol), _CMP_LT_OQ),
                             _mm256_cmp_pd(e, _mm256_sub_pd(x_hi, tol), _CMP_GT_OQ));
            if ((_mm256_movemask_pd(is_near) & ((1 << rows) - 1)) != 0) {
                // A centre within TOL of a bound: the tie rule decides it (rare).
                alignas(32) double bs[4];
                alignas(32) double es[4];
                alignas(32) double lo[4];
                alignas(32) double hi[4];
                _mm256_store_pd(bs, b);
                _mm256_store_pd(es, e);
                _mm256_store_pd(lo, x_lo);
                _mm256_store_pd(hi, x_hi);
                for (int r = 0; r < rows; ++r) {
                    if (bs[r] < lo[r] + TOL &&
                        !inside(t, static_cast<std::int64_t>(bs[r]), j + r, k)) {
                        bs[r] += 1.0;
                    }
                    if (es[r] > hi[r] - TOL &&
                        !inside(t, static_cast<std::int64_t>(es[r]), j + r, k)) {
                        es[r] -= 1.0;
                    }
                }
                b = _mm256_load_pd(bs);
                e = _mm256_load_pd(es);
            }
            const __m256d begin = _mm256_max_pd(b, box_lo);
            const __m256d end = _mm256_max_pd(begin, _mm256_add_pd(_mm256_min_pd(e, box_hi), one));
            alignas(32) double begins[4];
            alignas(32) double counts[4];
            alignas(32) double g_row[3][4];
            _mm256_store_pd(begins, begin);
            _mm256_store_pd(counts, _mm256_sub_pd(end, begin));
            for (int a = 0; a < 3; ++a) {
                _mm256_store_pd(g_row[a], _mm256_add_pd(g_k[a], _mm256_mul_pd(map_j[a], jd)));
            }
            // The rows' voxels: 4 entries each whatever its length (8 when longer).
            for (int r = 0; r < rows; ++r) {
                const int at = batch.num_voxels;
                const __m256d id = _mm256_add_pd(_mm256_set1_pd(begins[r]), lane);
                const std::int64_t base =
                    layer_base + (j + r) * nx + static_cast<std::int64_t>(begins[r]);
                const __m256i index = _mm256_add_epi64(_mm256_set1_epi64x(base), lane64);
                for (int a = 0; a < 3; ++a) {
                    _mm256_storeu_pd(batch.g[a] + at, _mm256_add_pd(_mm256_set1_pd(g_row[a][r]),
                                                                    _mm256_mul_pd(map_i[a], id)));
                }
                _mm256_storeu_si256(reinterpret_cast<__m256i*>(batch.index + at), index);
                const int n = static_cast<int>(counts[r]);
                if (n > 4) {
                    const __m256d id4 = _mm256_add_pd(id, four);
                    for (int a = 0; a < 3; ++a) {
                        _mm256_storeu_pd(batch.g[a] + at + 4,
                                         _mm256_add_pd(_mm256_set1_pd(g_row[a][r]),
                                                       _mm256_mul_pd(map_i[a], id4)));
                    }
                    _mm256_storeu_si256(reinterpret_cast<__m256i*>(batch.index + at + 4),
                                        _mm256_add_epi64(index, _mm256_set1_epi64x(4)));
                }
                batch.num_voxels += n;
                num_voxels += n;
            }
        }
    }
    return k_end;
}

PLIANT_AVX2_FN int sample_f32_avx2(const float* src, const std::int64_t n[3],
                                   const SpanBatch& batch, float scale, float* dst) {
    return batch.is_interior ? sample_f32<true>(src, n, batch, scale, dst)
                             : sample_f32<false>(src, n, batch, scale, dst);
}

#else  // no AVX2 on this target

bool has_avx2() {
    return false;
}
std::int64_t append_layers_avx2(const TetRaster&, std::int64_t k, std::int64_t, std::int64_t,
                                std::int64_t, SpanBatch&, std::int64_t&) {
    return k;
}
int sample_f32_avx2(const float*, const std::int64_t*, const SpanBatch&, float, float*) {
    return 0;
}

#endif

}  // namespace pliant::volume::detail
