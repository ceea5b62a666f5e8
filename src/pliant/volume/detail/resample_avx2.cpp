#include "pliant/volume/detail/resample_avx2.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <type_traits>

#include "pliant/core/simd_dispatch.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

#include "pliant/core/simd_avx2.hpp"
#endif

namespace pliant::volume::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

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
template <bool INTERIOR>
PLIANT_AVX2_INLINE Axis axis(__m256d g, __m256d top) {
    // std::clamp(g, 0, n − 1) (a no-op inside); max_pd returns its second operand for NaN
    // (masked out later).
    const __m256d c = INTERIOR ? g : _mm256_min_pd(_mm256_max_pd(g, _mm256_setzero_pd()), top);
    const __m128i i = _mm256_cvttpd_epi32(c);
    return {i, _mm256_cvtpd_ps(_mm256_sub_pd(c, _mm256_cvtepi32_pd(i)))};
}

// slice_rows() of layers k … k + 3 at once (a layer per lane; the same rows): rows
// [begin[l], end[l]) of layer k + l, as doubles.
PLIANT_AVX2_INLINE void slice_rows_of_layers(const TetRaster& t, std::int64_t k, double* begin,
                                             double* end) {
    constexpr double GROW = 1e-6;
    const __m256d z =
        _mm256_add_pd(_mm256_set1_pd(static_cast<double>(k)), _mm256_setr_pd(0.0, 1.0, 2.0, 3.0));
    const __m256d grow = _mm256_set1_pd(GROW);
    const __m256d inf = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    const __m256d neg_inf = _mm256_set1_pd(-std::numeric_limits<double>::infinity());
    __m256d y_min = inf;
    __m256d y_max = neg_inf;
    for (int e = 0; e < 6; ++e) {
        const __m256d z_lo = _mm256_set1_pd(t.edge_z_lo[e]);
        const __m256d z_hi = _mm256_set1_pd(t.edge_z_hi[e]);
        const __m256d is_crossed =
            _mm256_and_pd(_mm256_cmp_pd(z, _mm256_sub_pd(z_lo, grow), _CMP_GE_OQ),
                          _mm256_cmp_pd(z, _mm256_add_pd(z_hi, grow), _CMP_LE_OQ));
        // std::min(std::max(z, z_lo), z_hi)
        const __m256d zc = _mm256_min_pd(z_hi, _mm256_max_pd(z_lo, z));
        const __m256d y =
            _mm256_add_pd(_mm256_set1_pd(t.edge_y0[e]),
                          _mm256_mul_pd(_mm256_sub_pd(zc, _mm256_set1_pd(t.edge_z0[e])),
                                        _mm256_set1_pd(t.edge_slope[e])));
        y_min = _mm256_min_pd(_mm256_blendv_pd(inf, y, is_crossed), y_min);
        y_max = _mm256_max_pd(_mm256_blendv_pd(neg_inf, y, is_crossed), y_max);
    }
    // rows_of_extent() per lane.
    const __m256d lo = _mm256_set1_pd(static_cast<double>(t.lo[1]));
    const __m256d hi = _mm256_set1_pd(static_cast<double>(t.hi[1]));
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d lo_1 = _mm256_sub_pd(lo, one);
    const __m256d hi_1 = _mm256_add_pd(hi, one);
    const __m256d is_empty = _mm256_cmp_pd(y_min, y_max, _CMP_NLE_UQ);
    const __m256d b = _mm256_max_pd(
        _mm256_ceil_pd(_mm256_min_pd(_mm256_max_pd(_mm256_sub_pd(y_min, grow), lo_1), hi_1)), lo);
    const __m256d e = _mm256_add_pd(
        _mm256_min_pd(
            _mm256_floor_pd(_mm256_min_pd(_mm256_max_pd(_mm256_add_pd(y_max, grow), lo_1), hi_1)),
            hi),
        one);
    const __m256d zero = _mm256_setzero_pd();
    _mm256_store_pd(begin, _mm256_blendv_pd(b, zero, is_empty));
    _mm256_store_pd(end, _mm256_blendv_pd(e, zero, is_empty));
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
        const Axis ax = axis<INTERIOR>(gx, top_x);
        const Axis ay = axis<INTERIOR>(gy, top_y);
        const Axis az = axis<INTERIOR>(gz, top_z);
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

// The RGBA8 voxel at voxel index i (4 bytes) as the low 32 bits of a vector.
PLIANT_AVX2_INLINE __m128i voxel_rgba8(const std::uint8_t* src, std::int32_t i) {
    std::int32_t v = 0;
    std::memcpy(&v, src + 4 * static_cast<std::int64_t>(i), 4);
    return _mm_cvtsi32_si128(v);
}

// Two RGBA8 voxels (low 32 bits of a and b) as 8 floats: a's channels, then b's.
PLIANT_AVX2_INLINE __m256 widen_pair(__m128i a, __m128i b) {
    return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_unpacklo_epi32(a, b)));
}

// The voxels at a and b (any two) as 8 floats: a's channels, then b's.
PLIANT_AVX2_INLINE __m256 corner_pair_rgba8(const std::uint8_t* src, std::int32_t a,
                                            std::int32_t b) {
    return widen_pair(voxel_rgba8(src, a), voxel_rgba8(src, b));
}

// The corners (x, x + 1) of one row for the two voxels at a and b (interior: adjacent in
// memory), as {a's corner x, b's corner x} and {a's corner x + 1, b's corner x + 1}.
PLIANT_AVX2_INLINE void row_pair_rgba8(const std::uint8_t* src, std::int32_t a, std::int32_t b,
                                       __m256& lo, __m256& hi) {
    std::int64_t va = 0;
    std::int64_t vb = 0;
    std::memcpy(&va, src + 4 * static_cast<std::int64_t>(a), 8);
    std::memcpy(&vb, src + 4 * static_cast<std::int64_t>(b), 8);
    // 32-bit lanes: a0 a1 b0 b1 → a0 b0 a1 b1.
    const __m128i x = _mm_shuffle_epi32(_mm_set_epi64x(vb, va), _MM_SHUFFLE(3, 1, 2, 0));
    lo = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(x));
    hi = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_unpackhi_epi64(x, x)));
}

// u + f·(v − u) on 8 floats, the lerp of sample_trilinear.
PLIANT_AVX2_INLINE __m256 lerp8(__m256 u, __m256 v, __m256 f) {
    return _mm256_add_ps(u, _mm256_mul_ps(f, _mm256_sub_ps(v, u)));
}

// Lanes l and l + 1 of a 4-lane vector, each repeated 4 times (one voxel's channels).
PLIANT_AVX2_INLINE __m256 spread_pair(__m128 x, int l) {
    const __m256i idx = _mm256_setr_epi32(l, l, l, l, l + 1, l + 1, l + 1, l + 1);
    return _mm256_permutevar8x32_ps(_mm256_castps128_ps256(x), idx);
}

// The trilinear interpolation of 8 corner vectors (x fastest), sample_trilinear's order.
PLIANT_AVX2_INLINE __m256 trilinear8(__m256 v000, __m256 v100, __m256 v010, __m256 v110,
                                     __m256 v001, __m256 v101, __m256 v011, __m256 v111, __m256 fx,
                                     __m256 fy, __m256 fz) {
    const __m256 v00 = lerp8(v000, v100, fx);
    const __m256 v10 = lerp8(v010, v110, fx);
    const __m256 v01 = lerp8(v001, v101, fx);
    const __m256 v11 = lerp8(v011, v111, fx);
    const __m256 v0 = lerp8(v00, v10, fy);
    const __m256 v1 = lerp8(v01, v11, fy);
    return lerp8(v0, v1, fz);
}

// Per lane, the α of its voxel for the colour lanes and 1 for the α lanes (two RGBA voxels).
PLIANT_AVX2_INLINE __m256 alpha_or_one(__m256 v) {
    const __m256 alpha = _mm256_permutevar8x32_ps(v, _mm256_setr_epi32(3, 3, 3, 3, 7, 7, 7, 7));
    return _mm256_blend_ps(alpha, _mm256_set1_ps(1.0f), 0x88);
}

template <bool INTERIOR, typename D>
PLIANT_AVX2_INLINE int sample_rgba8(const std::uint8_t* src, const std::int64_t n[3],
                                    const SpanBatch& batch, float scale, D* dst) {
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
    const __m256 scale8 = _mm256_set1_ps(scale);
    const __m256 zero8 = _mm256_setzero_ps();
    const __m256 top8 = _mm256_set1_ps(255.0f);
    const __m256 half8 = _mm256_set1_ps(0.5f);
    const __m256i alpha_lanes = _mm256_setr_epi32(3, 3, 3, 3, 7, 7, 7, 7);
    for (int e = 0; e < count; e += 4) {
        const __m256d gx = _mm256_load_pd(batch.g[0] + e);
        const __m256d gy = _mm256_load_pd(batch.g[1] + e);
        const __m256d gz = _mm256_load_pd(batch.g[2] + e);
        const Axis ax = axis<INTERIOR>(gx, top_x);
        const Axis ay = axis<INTERIOR>(gy, top_y);
        const Axis az = axis<INTERIOR>(gz, top_z);
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
        alignas(16) std::int32_t at[4];
        alignas(16) std::int32_t dx[4];
        alignas(16) std::int32_t dy[4];
        alignas(16) std::int32_t dz[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(at), p);
        _mm_store_si128(reinterpret_cast<__m128i*>(dx), ox);
        _mm_store_si128(reinterpret_cast<__m128i*>(dy), oy);
        _mm_store_si128(reinterpret_cast<__m128i*>(dz), oz);
        __m128 in4 = _mm_castsi128_ps(_mm_set1_epi32(-1));
        if constexpr (!INTERIOR) {
            // 0 outside [−0.5, n − 0.5] on any axis (NaN too: ordered compares).
            const __m256d in =
                _mm256_and_pd(_mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(gx, half, _CMP_GE_OQ),
                                                          _mm256_cmp_pd(gx, end_x, _CMP_LE_OQ)),
                                            _mm256_and_pd(_mm256_cmp_pd(gy, half, _CMP_GE_OQ),
                                                          _mm256_cmp_pd(gy, end_y, _CMP_LE_OQ))),
                              _mm256_and_pd(_mm256_cmp_pd(gz, half, _CMP_GE_OQ),
                                            _mm256_cmp_pd(gz, end_z, _CMP_LE_OQ)));
            in4 = narrow_mask(in);
        }
        // Two voxels (lanes l, l + 1) per pass, their 4 channels side by side: each channel
        // gets sample_trilinear's operations in its order.
        for (int l = 0; l < 4; l += 2) {
            const std::int32_t a = at[l];
            const std::int32_t b = at[l + 1];
            __m256 v000, v100, v010, v110, v001, v101, v011, v111;
            if constexpr (INTERIOR) {
                row_pair_rgba8(src, a, b, v000, v100);
                row_pair_rgba8(src, a + nx, b + nx, v010, v110);
                row_pair_rgba8(src, a + nxy, b + nxy, v001, v101);
                row_pair_rgba8(src, a + nx + nxy, b + nx + nxy, v011, v111);
            } else {
                // (No lambda here: a lambda does not inherit the function's AVX2 target.)
                const std::int32_t xa = dx[l];
                const std::int32_t xb = dx[l + 1];
                const std::int32_t ya = dy[l];
                const std::int32_t yb = dy[l + 1];
                const std::int32_t za = dz[l];
                const std::int32_t zb = dz[l + 1];
                v000 = corner_pair_rgba8(src, a, b);
                v100 = corner_pair_rgba8(src, a + xa, b + xb);
                v010 = corner_pair_rgba8(src, a + ya, b + yb);
                v110 = corner_pair_rgba8(src, a + ya + xa, b + yb + xb);
                v001 = corner_pair_rgba8(src, a + za, b + zb);
                v101 = corner_pair_rgba8(src, a + za + xa, b + zb + xb);
                v011 = corner_pair_rgba8(src, a + za + ya, b + zb + yb);
                v111 = corner_pair_rgba8(src, a + za + ya + xa, b + zb + yb + xb);
            }
            const __m256 fx = spread_pair(ax.fraction, l);
            const __m256 fy = spread_pair(ay.fraction, l);
            const __m256 fz = spread_pair(az.fraction, l);
            // Opacity-weighted colours (interpolate_corners): each corner's colour · its α, the
            // α lanes · 1; straight again by the interpolated α where it is > 0, else the plain
            // interpolation.
            const __m256 weighted = trilinear8(
                _mm256_mul_ps(v000, alpha_or_one(v000)), _mm256_mul_ps(v100, alpha_or_one(v100)),
                _mm256_mul_ps(v010, alpha_or_one(v010)), _mm256_mul_ps(v110, alpha_or_one(v110)),
                _mm256_mul_ps(v001, alpha_or_one(v001)), _mm256_mul_ps(v101, alpha_or_one(v101)),
                _mm256_mul_ps(v011, alpha_or_one(v011)), _mm256_mul_ps(v111, alpha_or_one(v111)),
                fx, fy, fz);
            const __m256 alpha = _mm256_permutevar8x32_ps(weighted, alpha_lanes);
            const __m256 opaque = _mm256_cmp_ps(alpha, zero8, _CMP_GT_OQ);
            __m256 v = _mm256_div_ps(weighted, alpha);
            if (_mm256_movemask_ps(opaque) != 0xFF) {
                const __m256 plain =
                    trilinear8(v000, v100, v010, v110, v001, v101, v011, v111, fx, fy, fz);
                v = _mm256_blendv_ps(plain, v, opaque);
            }
            v = _mm256_blend_ps(v, weighted, 0x88);
            if constexpr (!INTERIOR) {
                v = _mm256_and_ps(v, spread_pair(in4, l));
            }
            D* out_a = dst + 4 * batch.index[e + l];
            D* out_b = dst + 4 * batch.index[e + l + 1];
            if constexpr (std::is_same_v<D, float>) {
                // convert_sample<float>: v · scale.
                v = _mm256_mul_ps(v, scale8);
                _mm_storeu_ps(out_a, _mm256_castps256_ps128(v));
                _mm_storeu_ps(out_b, _mm256_extractf128_ps(v, 1));
            } else {
                // convert_sample<uint8_t>: v > 0 ? (v < 255 ? v : 255) : 0 (NaN → 0; max_ps
                // returns its second operand unless the first is greater), + 0.5, truncated.
                const __m256 c = _mm256_min_ps(_mm256_max_ps(v, zero8), top8);
                const __m256i i = _mm256_cvttps_epi32(_mm256_add_ps(c, half8));
                const __m128i w =
                    _mm_packus_epi32(_mm256_castsi256_si128(i), _mm256_extracti128_si256(i, 1));
                const __m128i bytes = _mm_packus_epi16(w, w);
                const std::int64_t both = _mm_cvtsi128_si64(bytes);
                std::memcpy(out_a, &both, 4);
                std::memcpy(out_b, reinterpret_cast<const char*>(&both) + 4, 4);
            }
        }
    }
    return count;
}

// Four lanes of doubles: one per tet.
using V = __m256d;
using simd::add;
using simd::mul;
using simd::select;
using simd::set1;
using simd::sub;
struct V3 {
    V x, y, z;
};
// std::min(a, b) and std::max(a, b), NaN and signed zeros included.
PLIANT_AVX2_INLINE V std_min(V a, V b) {
    return _mm256_min_pd(b, a);
}
PLIANT_AVX2_INLINE V std_max(V a, V b) {
    return _mm256_max_pd(b, a);
}
PLIANT_AVX2_INLINE V3 sub(const V3& a, const V3& b) {
    return {sub(a.x, b.x), sub(a.y, b.y), sub(a.z, b.z)};
}
PLIANT_AVX2_INLINE V3 scale(const V3& a, V s) {
    return {mul(a.x, s), mul(a.y, s), mul(a.z, s)};
}
// cross() and dot() of core/vec3.hpp, the same operations.
PLIANT_AVX2_INLINE V3 cross(const V3& a, const V3& b) {
    return {sub(mul(a.y, b.z), mul(a.z, b.y)), sub(mul(a.z, b.x), mul(a.x, b.z)),
            sub(mul(a.x, b.y), mul(a.y, b.x))};
}
PLIANT_AVX2_INLINE V dot(const V3& a, const V3& b) {
    return add(add(mul(a.x, b.x), mul(a.y, b.y)), mul(a.z, b.z));
}
PLIANT_AVX2_INLINE V is_finite(V x) {
    const V abs = _mm256_andnot_pd(set1(-0.0), x);
    return _mm256_cmp_pd(abs, set1(std::numeric_limits<double>::infinity()), _CMP_LT_OQ);
}
PLIANT_AVX2_INLINE V component(const V3& v, int a) {
    return a == 0 ? v.x : (a == 1 ? v.y : v.z);
}
// setup_tet()'s compare-exchange of sorted vertices x < y by vertex index, per lane.
PLIANT_AVX2_INLINE void sort2(V3 sorted[4], V sorted_id[4], int x, int y) {
    const V swap = _mm256_cmp_pd(sorted_id[y], sorted_id[x], _CMP_LT_OQ);
    const V3 vx = sorted[x];
    const V3 vy = sorted[y];
    sorted[x] = {select(swap, vy.x, vx.x), select(swap, vy.y, vx.y), select(swap, vy.z, vx.z)};
    sorted[y] = {select(swap, vx.x, vy.x), select(swap, vx.y, vy.y), select(swap, vx.z, vy.z)};
    const V ix = sorted_id[x];
    sorted_id[x] = select(swap, sorted_id[y], ix);
    sorted_id[y] = select(swap, ix, sorted_id[y]);
}
// Lane l of v[0 .. 4) as 4 consecutive doubles at out[l] (a 4 × 4 transpose).
PLIANT_AVX2_INLINE void store_transposed(const V v[4], double* out0, double* out1, double* out2,
                                         double* out3) {
    const V t0 = _mm256_unpacklo_pd(v[0], v[1]);  // v0[0] v1[0] v0[2] v1[2]
    const V t1 = _mm256_unpackhi_pd(v[0], v[1]);  // v0[1] v1[1] v0[3] v1[3]
    const V t2 = _mm256_unpacklo_pd(v[2], v[3]);
    const V t3 = _mm256_unpackhi_pd(v[2], v[3]);
    _mm256_storeu_pd(out0, _mm256_permute2f128_pd(t0, t2, 0x20));
    _mm256_storeu_pd(out1, _mm256_permute2f128_pd(t1, t3, 0x20));
    _mm256_storeu_pd(out2, _mm256_permute2f128_pd(t0, t2, 0x31));
    _mm256_storeu_pd(out3, _mm256_permute2f128_pd(t1, t3, 0x31));
}

}  // namespace

PLIANT_AVX2_FN int setup_tets_avx2(const Vec3f* deformed, const Vec3f* rest_positions,
                                   const std::int32_t ids[4][4], const RestInfo rest[4],
                                   const GridFrame& target, const GridFrame& source,
                                   TetRaster out[4]) {
    constexpr double INF = std::numeric_limits<double>::infinity();
    constexpr double GROW = 1e-6;
    const V inf = set1(INF);
    const V neg_inf = set1(-INF);
    const V zero = _mm256_setzero_pd();
    // Vertices (float → double is exact).
    V3 pd[4];
    V3 rd[4];
    V id[4];
    for (int v = 0; v < 4; ++v) {
        const Vec3f& p0 = deformed[ids[0][v]];
        const Vec3f& p1 = deformed[ids[1][v]];
        const Vec3f& p2 = deformed[ids[2][v]];
        const Vec3f& p3 = deformed[ids[3][v]];
        const Vec3f& r0 = rest_positions[ids[0][v]];
        const Vec3f& r1 = rest_positions[ids[1][v]];
        const Vec3f& r2 = rest_positions[ids[2][v]];
        const Vec3f& r3 = rest_positions[ids[3][v]];
        pd[v] = {_mm256_cvtps_pd(_mm_setr_ps(p0.x, p1.x, p2.x, p3.x)),
                 _mm256_cvtps_pd(_mm_setr_ps(p0.y, p1.y, p2.y, p3.y)),
                 _mm256_cvtps_pd(_mm_setr_ps(p0.z, p1.z, p2.z, p3.z))};
        rd[v] = {_mm256_cvtps_pd(_mm_setr_ps(r0.x, r1.x, r2.x, r3.x)),
                 _mm256_cvtps_pd(_mm_setr_ps(r0.y, r1.y, r2.y, r3.y)),
                 _mm256_cvtps_pd(_mm_setr_ps(r0.z, r1.z, r2.z, r3.z))};
        id[v] = _mm256_cvtepi32_pd(_mm_setr_epi32(ids[0][v], ids[1][v], ids[2][v], ids[3][v]));
    }
    // Index coordinates and the box (axis_range).
    V vertex[4][3];
    for (int v = 0; v < 4; ++v) {
        const V c[3] = {pd[v].x, pd[v].y, pd[v].z};
        for (int a = 0; a < 3; ++a) {
            vertex[v][a] =
                sub(mul(sub(c[a], set1(target.origin[a])), set1(target.inv_spacing[a])), set1(0.5));
        }
    }
    alignas(32) double box_lo[3][4];
    alignas(32) double box_hi[3][4];
    for (int a = 0; a < 3; ++a) {
        const V mn =
            std_min(std_min(vertex[0][a], vertex[1][a]), std_min(vertex[2][a], vertex[3][a]));
        const V mx =
            std_max(std_max(vertex[0][a], vertex[1][a]), std_max(vertex[2][a], vertex[3][a]));
        const V top = set1(static_cast<double>(target.n[a]));
        const V minus_one = set1(-1.0);
        const V lo =
            _mm256_ceil_pd(_mm256_min_pd(_mm256_max_pd(sub(mn, set1(GROW)), minus_one), top));
        const V hi =
            _mm256_floor_pd(_mm256_min_pd(_mm256_max_pd(add(mx, set1(GROW)), minus_one), top));
        _mm256_store_pd(box_lo[a], _mm256_max_pd(lo, zero));
        _mm256_store_pd(box_hi[a], _mm256_min_pd(hi, set1(static_cast<double>(target.n[a] - 1))));
    }
    for (int l = 0; l < 4; ++l) {
        for (int a = 0; a < 3; ++a) {
            out[l].lo[a] = static_cast<std::int64_t>(box_lo[a][l]);
            out[l].hi[a] = static_cast<std::int64_t>(box_hi[a][l]);
        }
    }

    // T, det T, T⁻¹.
    const V3 e0 = sub(pd[0], pd[3]);
    const V3 e1 = sub(pd[1], pd[3]);
    const V3 e2 = sub(pd[2], pd[3]);
    const V3 c12 = cross(e1, e2);
    const V det = dot(e0, c12);
    const V inv_det = _mm256_div_pd(set1(1.0), det);
    V ok = _mm256_and_pd(_mm256_cmp_pd(det, zero, _CMP_NEQ_UQ), is_finite(inv_det));

    // Faces, from the vertices sorted by vertex index.
    const V3 c0{set1(target.origin[0] + 0.5 * target.spacing[0]),
                set1(target.origin[1] + 0.5 * target.spacing[1]),
                set1(target.origin[2] + 0.5 * target.spacing[2])};
    V3 sorted[4] = {pd[0], pd[1], pd[2], pd[3]};
    V sorted_id[4] = {id[0], id[1], id[2], id[3]};
    sort2(sorted, sorted_id, 0, 1);
    sort2(sorted, sorted_id, 2, 3);
    sort2(sorted, sorted_id, 0, 2);
    sort2(sorted, sorted_id, 1, 3);
    sort2(sorted, sorted_id, 1, 2);
    constexpr int OTHERS[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    V plane[4][4];
    V tie[4];
    for (int m = 0; m < 4; ++m) {
        const V3& u = sorted[OTHERS[m][0]];
        const V3 n = cross(sub(sorted[OTHERS[m][1]], u), sub(sorted[OTHERS[m][2]], u));
        const V side = dot(n, sub(sorted[m], u));
        ok = _mm256_and_pd(ok, _mm256_cmp_pd(side, zero, _CMP_NEQ_UQ));
        const V sigma = select(_mm256_cmp_pd(side, zero, _CMP_GT_OQ), set1(1.0), set1(-1.0));
        const V3 c = sub(c0, u);
        const V delta = add(add(mul(n.x, c.x), mul(n.y, c.y)), mul(n.z, c.z));
        plane[m][0] = mul(sigma, mul(n.x, set1(target.spacing[0])));
        plane[m][1] = mul(sigma, mul(n.y, set1(target.spacing[1])));
        plane[m][2] = mul(sigma, mul(n.z, set1(target.spacing[2])));
        plane[m][3] = mul(sigma, delta);
        // Lexicographically positive inward normal (NaN components are not positive).
        const V3 inward = scale(n, sigma);
        const V x_pos = _mm256_cmp_pd(inward.x, zero, _CMP_GT_OQ);
        const V x_zero = _mm256_cmp_pd(inward.x, zero, _CMP_EQ_OQ);
        const V y_pos = _mm256_cmp_pd(inward.y, zero, _CMP_GT_OQ);
        const V y_zero = _mm256_cmp_pd(inward.y, zero, _CMP_EQ_OQ);
        const V z_pos = _mm256_cmp_pd(inward.z, zero, _CMP_GT_OQ);
        tie[m] = _mm256_or_pd(
            x_pos, _mm256_and_pd(x_zero, _mm256_or_pd(y_pos, _mm256_and_pd(y_zero, z_pos))));
    }
    const int ok_mask = _mm256_movemask_pd(ok);

    // Row spans: per face −1/a (0 for a = 0), caps and floors.
    V neg_inv_a[4];
    V cap[4];
    V floor[4];
    V is_fast = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
    V flat[4];
    for (int m = 0; m < 4; ++m) {
        const V a = plane[m][0];
        flat[m] = _mm256_cmp_pd(a, zero, _CMP_EQ_OQ);
        const V root = _mm256_div_pd(set1(-1.0), a);
        neg_inv_a[m] = select(flat[m], zero, root);
        is_fast = _mm256_and_pd(
            is_fast, _mm256_or_pd(flat[m], _mm256_and_pd(is_finite(root),
                                                         _mm256_cmp_pd(root, zero, _CMP_NEQ_UQ))));
        const V signed_inf = select(_mm256_cmp_pd(a, zero, _CMP_GT_OQ), inf, neg_inf);
        cap[m] = select(flat[m], neg_inf, signed_inf);
        floor[m] = select(flat[m], inf, signed_inf);
    }

    // Cross-sections: the edges in index space (entries 6 and 7: padding).
    constexpr int EDGES[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    V edge_z_lo[8];
    V edge_z_hi[8];
    V edge_y0[8];
    V edge_z0[8];
    V edge_slope[8];
    for (int e = 0; e < 6; ++e) {
        const V* va = vertex[EDGES[e][0]];
        const V* vb = vertex[EDGES[e][1]];
        const V dz = sub(vb[2], va[2]);
        const V is_flat = _mm256_cmp_pd(dz, zero, _CMP_EQ_OQ);
        edge_z_lo[e] = select(is_flat, inf, std_min(va[2], vb[2]));
        edge_z_hi[e] = select(is_flat, neg_inf, std_max(va[2], vb[2]));
        edge_y0[e] = va[1];
        edge_z0[e] = va[2];
        edge_slope[e] = select(is_flat, zero, _mm256_div_pd(sub(vb[1], va[1]), dz));
    }
    for (int e = 6; e < 8; ++e) {
        edge_z_lo[e] = inf;
        edge_z_hi[e] = neg_inf;
        edge_y0[e] = zero;
        edge_z0[e] = zero;
        edge_slope[e] = zero;
    }

    // The affine map target index → source grid coordinate.
    const V3 row[3] = {scale(c12, inv_det), scale(cross(e2, e0), inv_det),
                       scale(cross(e0, e1), inv_det)};
    const V3 f[3] = {sub(rd[0], rd[3]), sub(rd[1], rd[3]), sub(rd[2], rd[3])};
    const V3 x0 = sub(c0, pd[3]);
    V map[3][4];
    for (int a = 0; a < 3; ++a) {
        V mm[3];
        for (int b = 0; b < 3; ++b) {
            mm[b] = add(add(mul(component(f[0], a), component(row[0], b)),
                            mul(component(f[1], a), component(row[1], b))),
                        mul(component(f[2], a), component(row[2], b)));
        }
        const V inv_s = set1(source.inv_spacing[a]);
        for (int b = 0; b < 3; ++b) {
            map[a][b] = mul(mul(mm[b], set1(target.spacing[b])), inv_s);
        }
        const V rest0 = add(component(rd[3], a),
                            add(add(mul(mm[0], x0.x), mul(mm[1], x0.y)), mul(mm[2], x0.z)));
        map[a][3] = sub(mul(sub(rest0, set1(source.origin[a])), inv_s), set1(0.5));
    }

    // Out, lane by lane.
    for (int m = 0; m < 4; ++m) {
        store_transposed(plane[m], out[0].plane[m], out[1].plane[m], out[2].plane[m],
                         out[3].plane[m]);
    }
    store_transposed(neg_inv_a, out[0].neg_inv_a, out[1].neg_inv_a, out[2].neg_inv_a,
                     out[3].neg_inv_a);
    store_transposed(cap, out[0].root_cap, out[1].root_cap, out[2].root_cap, out[3].root_cap);
    store_transposed(floor, out[0].root_floor, out[1].root_floor, out[2].root_floor,
                     out[3].root_floor);
    for (int h = 0; h < 8; h += 4) {
        store_transposed(edge_z_lo + h, out[0].edge_z_lo + h, out[1].edge_z_lo + h,
                         out[2].edge_z_lo + h, out[3].edge_z_lo + h);
        store_transposed(edge_z_hi + h, out[0].edge_z_hi + h, out[1].edge_z_hi + h,
                         out[2].edge_z_hi + h, out[3].edge_z_hi + h);
        store_transposed(edge_y0 + h, out[0].edge_y0 + h, out[1].edge_y0 + h, out[2].edge_y0 + h,
                         out[3].edge_y0 + h);
        store_transposed(edge_z0 + h, out[0].edge_z0 + h, out[1].edge_z0 + h, out[2].edge_z0 + h,
                         out[3].edge_z0 + h);
        store_transposed(edge_slope + h, out[0].edge_slope + h, out[1].edge_slope + h,
                         out[2].edge_slope + h, out[3].edge_slope + h);
    }
    for (int a = 0; a < 3; ++a) {
        store_transposed(map[a], out[0].map[a], out[1].map[a], out[2].map[a], out[3].map[a]);
    }
    alignas(32) double det_l[4];
    _mm256_store_pd(det_l, det);
    int tie_bits[4];
    int flat_bits[4];
    for (int m = 0; m < 4; ++m) {
        tie_bits[m] = _mm256_movemask_pd(tie[m]);
        flat_bits[m] = _mm256_movemask_pd(flat[m]);
    }
    const int fast_bits = _mm256_movemask_pd(is_fast);
    for (int l = 0; l < 4; ++l) {
        TetRaster& t = out[l];
        t.is_inverted = (det_l[l] > 0.0 && rest[l].orientation < 0) ||
                        (det_l[l] < 0.0 && rest[l].orientation > 0);
        t.is_interior = rest[l].is_interior;
        t.is_fast = ((fast_bits >> l) & 1) != 0;
        t.flat_faces = 0;
        t.k_lo = t.lo[2];
        t.k_hi = t.hi[2];
        for (int m = 0; m < 4; ++m) {
            t.tie_inside[m] = ((tie_bits[m] >> l) & 1) != 0;
        }
        if (((ok_mask >> l) & 1) == 0) {
            continue;
        }
        for (int m = 0; m < 4; ++m) {
            if (((flat_bits[m] >> l) & 1) == 0) {
                continue;
            }
            if (t.plane[m][1] != 0.0) {
                t.flat_faces = static_cast<std::uint8_t>(t.flat_faces | (1 << m));
            } else {
                narrow_flat_layers(t, m);
            }
        }
    }
    return ok_mask;
}

// Per lane, v[l] of the lane's layer l: v[0], v[1] where in1, v[2] where in2, v[3] where in3
// (nested masks).
PLIANT_AVX2_INLINE __m256d by_layer(const double v[4], __m256d in1, __m256d in2, __m256d in3) {
    __m256d r = _mm256_blendv_pd(_mm256_set1_pd(v[0]), _mm256_set1_pd(v[1]), in1);
    r = _mm256_blendv_pd(r, _mm256_set1_pd(v[2]), in2);
    return _mm256_blendv_pd(r, _mm256_set1_pd(v[3]), in3);
}
constexpr double LAYER[4] = {0.0, 1.0, 2.0, 3.0};

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
    const __m256d row_size = _mm256_set1_pd(static_cast<double>(nx));
    const __m256d layer_size = _mm256_set1_pd(static_cast<double>(nxy));
    const std::int64_t k0 = std::max(t.k_lo, k);
    const std::int64_t k1 = std::min(t.k_hi + 1, k_end);
    batch.is_interior = batch.is_interior && t.is_interior;
    int filled = batch.num_voxels;  // kept in a register, stored on return
    // Chunks of up to 4 layers; their rows, layer by layer, fill the lanes 4 at a time.
    for (std::int64_t kc = k0; kc < k1; kc += 4) {
        alignas(32) double rows_begin[4];
        alignas(32) double rows_end[4];
        slice_rows_of_layers(t, kc, rows_begin, rows_end);
        const int layers = static_cast<int>(std::min<std::int64_t>(4, k1 - kc));
        if (t.flat_faces != 0) {
            for (int l = 0; l < layers; ++l) {
                auto j0 = static_cast<std::int64_t>(rows_begin[l]);
                auto j1 = static_cast<std::int64_t>(rows_end[l]);
                flat_rows(t, kc + l, j0, j1);
                rows_begin[l] = static_cast<double>(j0);
                rows_end[l] = static_cast<double>(j1);
            }
        }
        // offsets[l]: the rows of the chunk before layer l.
        double offsets[4];
        double total = 0.0;
        for (int l = 0; l < 4; ++l) {
            offsets[l] = total;
            total += l < layers ? std::max(rows_end[l] - rows_begin[l], 0.0) : 0.0;
        }
        const auto num_rows = static_cast<std::int64_t>(total);
        // Each row writes at most 8 entries (the tet is at most 8 voxels wide).
        if (filled + num_rows * 8 > SpanBatch::CAPACITY) {
            num_voxels += filled - batch.num_voxels;
            batch.num_voxels = filled;
            return kc;
        }
        const __m256d offset1 = _mm256_set1_pd(offsets[1]);
        const __m256d offset2 = _mm256_set1_pd(offsets[2]);
        const __m256d offset3 = _mm256_set1_pd(offsets[3]);
        for (std::int64_t first = 0; first < num_rows; first += 4) {
            // Lane: the chunk's row `first + lane`, in layer l (the last layer whose offset it
            // reaches; the masks are nested since the offsets increase).
            const __m256d index = _mm256_add_pd(_mm256_set1_pd(static_cast<double>(first)), lane);
            const __m256d in1 = _mm256_cmp_pd(index, offset1, _CMP_GE_OQ);
            const __m256d in2 = _mm256_cmp_pd(index, offset2, _CMP_GE_OQ);
            const __m256d in3 = _mm256_cmp_pd(index, offset3, _CMP_GE_OQ);
            const __m256d jd =
                _mm256_add_pd(by_layer(rows_begin, in1, in2, in3),
                              _mm256_sub_pd(index, by_layer(offsets, in1, in2, in3)));
            const double kcd = static_cast<double>(kc);
            const __m256d kd = _mm256_add_pd(_mm256_set1_pd(kcd), by_layer(LAYER, in1, in2, in3));
            // row_span_fast() lane by lane.
            __m256d x_lo = x_lo0;
            __m256d x_hi = x_hi0;
            for (int q = 0; q < 4; ++q) {
                const __m256d gamma =
                    _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(t.plane[q][2]), kd),
                                  _mm256_set1_pd(t.plane[q][3]));
                const __m256d beta =
                    _mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(t.plane[q][1]), jd), gamma);
                const __m256d root = _mm256_mul_pd(beta, _mm256_set1_pd(t.neg_inv_a[q]));
                x_lo = _mm256_max_pd(x_lo, _mm256_min_pd(root, _mm256_set1_pd(t.root_cap[q])));
                x_hi = _mm256_min_pd(x_hi, _mm256_max_pd(root, _mm256_set1_pd(t.root_floor[q])));
            }
            x_lo = _mm256_min_pd(x_lo, lo_cap);
            x_hi = _mm256_max_pd(x_hi, hi_floor);
            __m256d b = _mm256_ceil_pd(_mm256_sub_pd(x_lo, tol));
            __m256d e = _mm256_floor_pd(_mm256_add_pd(x_hi, tol));
            const int rows = static_cast<int>(std::min<std::int64_t>(4, num_rows - first));
            const __m256d is_near =
                _mm256_or_pd(_mm256_cmp_pd(b, _mm256_add_pd(x_lo, tol), _CMP_LT_OQ),
                             _mm256_cmp_pd(e, _mm256_sub_pd(x_hi, tol), _CMP_GT_OQ));
            if ((_mm256_movemask_pd(is_near) & ((1 << rows) - 1)) != 0) {
                // A centre within TOL of a bound: the tie rule decides it (rare).
                alignas(32) double bs[4];
                alignas(32) double es[4];
                alignas(32) double lo[4];
                alignas(32) double hi[4];
                alignas(32) double js[4];
                alignas(32) double ks[4];
                _mm256_store_pd(bs, b);
                _mm256_store_pd(es, e);
                _mm256_store_pd(lo, x_lo);
                _mm256_store_pd(hi, x_hi);
                _mm256_store_pd(js, jd);
                _mm256_store_pd(ks, kd);
                for (int r = 0; r < rows; ++r) {
                    const auto j = static_cast<std::int64_t>(js[r]);
                    const auto kr = static_cast<std::int64_t>(ks[r]);
                    if (bs[r] < lo[r] + TOL &&
                        !inside(t, static_cast<std::int64_t>(bs[r]), j, kr)) {
                        bs[r] += 1.0;
                    }
                    if (es[r] > hi[r] - TOL &&
                        !inside(t, static_cast<std::int64_t>(es[r]), j, kr)) {
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
            alignas(32) double bases[4];
            alignas(32) double g_row[3][4];
            _mm256_store_pd(begins, begin);
            _mm256_store_pd(counts, _mm256_sub_pd(end, begin));
            // Linear index of voxel (begin, j, k) (exact in doubles).
            _mm256_store_pd(bases, _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(kd, layer_size),
                                                               _mm256_mul_pd(jd, row_size)),
                                                 begin));
            for (int a = 0; a < 3; ++a) {
                // (map[a][3] + map[a][2]·k) + map[a][1]·j, append_spans()'s order.
                const __m256d g_k = _mm256_add_pd(_mm256_set1_pd(t.map[a][3]),
                                                  _mm256_mul_pd(_mm256_set1_pd(t.map[a][2]), kd));
                _mm256_store_pd(g_row[a],
                                _mm256_add_pd(g_k, _mm256_mul_pd(_mm256_set1_pd(t.map[a][1]), jd)));
            }
            // The rows' voxels: 4 entries each whatever its length (8 when longer).
            for (int r = 0; r < rows; ++r) {
                const int at = filled;
                const __m256d id = _mm256_add_pd(_mm256_set1_pd(begins[r]), lane);
                const __m256i index64 = _mm256_add_epi64(
                    _mm256_set1_epi64x(static_cast<std::int64_t>(bases[r])), lane64);
                for (int a = 0; a < 3; ++a) {
                    _mm256_storeu_pd(batch.g[a] + at,
                                     _mm256_add_pd(_mm256_set1_pd(g_row[a][r]),
                                                   _mm256_mul_pd(_mm256_set1_pd(t.map[a][0]), id)));
                }
                _mm256_storeu_si256(reinterpret_cast<__m256i*>(batch.index + at), index64);
                const int n = static_cast<int>(counts[r]);
                if (n > 4) {
                    const __m256d id4 = _mm256_add_pd(id, four);
                    for (int a = 0; a < 3; ++a) {
                        _mm256_storeu_pd(
                            batch.g[a] + at + 4,
                            _mm256_add_pd(_mm256_set1_pd(g_row[a][r]),
                                          _mm256_mul_pd(_mm256_set1_pd(t.map[a][0]), id4)));
                    }
                    _mm256_storeu_si256(reinterpret_cast<__m256i*>(batch.index + at + 4),
                                        _mm256_add_epi64(index64, _mm256_set1_epi64x(4)));
                }
                filled += n;
            }
        }
    }
    num_voxels += filled - batch.num_voxels;
    batch.num_voxels = filled;
    return k_end;
}

PLIANT_AVX2_FN int sample_f32_avx2(const float* src, const std::int64_t n[3],
                                   const SpanBatch& batch, float scale, float* dst) {
    return batch.is_interior ? sample_f32<true>(src, n, batch, scale, dst)
                             : sample_f32<false>(src, n, batch, scale, dst);
}

PLIANT_AVX2_FN int sample_rgba8_avx2(const std::uint8_t* src, const std::int64_t n[3],
                                     const SpanBatch& batch, float scale, std::uint8_t* dst) {
    return batch.is_interior ? sample_rgba8<true>(src, n, batch, scale, dst)
                             : sample_rgba8<false>(src, n, batch, scale, dst);
}

PLIANT_AVX2_FN int sample_rgba8_avx2(const std::uint8_t* src, const std::int64_t n[3],
                                     const SpanBatch& batch, float scale, float* dst) {
    return batch.is_interior ? sample_rgba8<true>(src, n, batch, scale, dst)
                             : sample_rgba8<false>(src, n, batch, scale, dst);
}

#else  // no AVX2 on this target
int setup_tets_avx2(const Vec3f*, const Vec3f*, const std::int32_t[4][4], const RestInfo[4],
                    const GridFrame&, const GridFrame&, TetRaster[4]) {
    return 0;
}
std::int64_t append_layers_avx2(const TetRaster&, std::int64_t k, std::int64_t, std::int64_t,
                                std::int64_t, SpanBatch&, std::int64_t&) {
    return k;
}
int sample_f32_avx2(const float*, const std::int64_t*, const SpanBatch&, float, float*) {
    return 0;
}
int sample_rgba8_avx2(const std::uint8_t*, const std::int64_t*, const SpanBatch&, float,
                      std::uint8_t*) {
    return 0;
}
int sample_rgba8_avx2(const std::uint8_t*, const std::int64_t*, const SpanBatch&, float, float*) {
    return 0;
}

#endif

}  // namespace pliant::volume::detail
