// Trilinear sampling of a RayCastKernel's grid for 8 lanes in AVX2, shared by the ray caster
// (raycast_avx2.cpp) and the mapped ray caster (mapped_raycast_avx2.cpp): locate() and
// interpolate_rgba() of raycast_kernel.hpp, lane by lane the scalar kernel's IEEE operations in
// the same order without FMA (core/simd_dispatch.hpp), so results are bitwise the scalar ones.
// Every function carries PLIANT_AVX2_INLINE (the AVX2 target and always_inline): a helper
// without the target inside an AVX2 function breaks the portable build (scripts/check-portable).
// Voxels, voxel pairs, bytes and lookup-table entries are loaded per lane (no gathers, see
// raycast_avx2.hpp).
#pragma once

#include <cstdint>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

namespace pliant::render::detail {

inline constexpr int LANES = 8;

// a + t (b − a) lane by lane, as lerp().
PLIANT_AVX2_INLINE __m256 lerp8(__m256 a, __m256 b, __m256 t) {
    return _mm256_add_ps(a, _mm256_mul_ps(t, _mm256_sub_ps(b, a)));
}

// clampf(v, lo, hi) lane by lane: max(lo, v) keeps v where v < lo is false (NaN too), then
// min(hi, ·) keeps it where hi < it is false.
PLIANT_AVX2_INLINE __m256 clamp8(__m256 v, __m256 lo, __m256 hi) {
    return _mm256_min_ps(hi, _mm256_max_ps(lo, v));
}

PLIANT_AVX2_INLINE __m256 load(const float* p) {
    return _mm256_load_ps(p);
}
PLIANT_AVX2_INLINE __m256i load(const std::int32_t* p) {
    return _mm256_load_si256(reinterpret_cast<const __m256i*>(p));
}
PLIANT_AVX2_INLINE void store(float* p, __m256 v) {
    _mm256_store_ps(p, v);
}
PLIANT_AVX2_INLINE void store(std::int32_t* p, __m256i v) {
    _mm256_store_si256(reinterpret_cast<__m256i*>(p), v);
}
// Per-lane loads instead of AVX2 gathers: on AMD Zen a gather of 8 floats costs as much as about
// 20 scalar loads even from L1, and x-adjacent voxels are loaded in pairs.

// base[index[l]] per lane l (bytes).
PLIANT_AVX2_INLINE __m256i load_bytes(const std::uint8_t* base, const std::int32_t* index) {
    return _mm256_setr_epi32(base[index[0]], base[index[1]], base[index[2]], base[index[3]],
                             base[index[4]], base[index[5]], base[index[6]], base[index[7]]);
}

// (v[i0], v[i0 + 1], v[i1], v[i1 + 1]).
PLIANT_AVX2_INLINE __m128 two_pairs(const float* v, std::int32_t i0, std::int32_t i1) {
    const __m128 low = _mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(v + i0)));
    return _mm_loadh_pi(low, reinterpret_cast<const __m64*>(v + i1));
}

// The pairs (v[index[l]], v[index[l] + 1]) of the 8 lanes as the vectors of their first and
// second elements.
PLIANT_AVX2_INLINE void load_pairs(const float* v, const std::int32_t* index, __m256& first,
                                   __m256& second) {
    // a = x0 y0 x1 y1 | x4 y4 x5 y5, b = x2 y2 x3 y3 | x6 y6 x7 y7.
    const __m256 a =
        _mm256_set_m128(two_pairs(v, index[4], index[5]), two_pairs(v, index[0], index[1]));
    const __m256 b =
        _mm256_set_m128(two_pairs(v, index[6], index[7]), two_pairs(v, index[2], index[3]));
    first = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0));
    second = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1));
}

// The 4 floats at lut + offset[l] per lane, transposed: out[c] holds component c of the 8 lanes.
PLIANT_AVX2_INLINE __m256 entry_row(const float* lut, const std::int32_t* offset, int l) {
    return _mm256_set_m128(_mm_loadu_ps(lut + offset[l + 4]), _mm_loadu_ps(lut + offset[l]));
}
PLIANT_AVX2_INLINE void load_entries(const float* lut, const std::int32_t* offset, __m256 out[4]) {
    const __m256 r0 = entry_row(lut, offset, 0);  // lanes 0 | 4
    const __m256 r1 = entry_row(lut, offset, 1);
    const __m256 r2 = entry_row(lut, offset, 2);
    const __m256 r3 = entry_row(lut, offset, 3);
    const __m256 t0 = _mm256_unpacklo_ps(r0, r1);
    const __m256 t1 = _mm256_unpacklo_ps(r2, r3);
    const __m256 t2 = _mm256_unpackhi_ps(r0, r1);
    const __m256 t3 = _mm256_unpackhi_ps(r2, r3);
    out[0] = _mm256_shuffle_ps(t0, t1, 0x44);
    out[1] = _mm256_shuffle_ps(t0, t1, 0xEE);
    out[2] = _mm256_shuffle_ps(t2, t3, 0x44);
    out[3] = _mm256_shuffle_ps(t2, t3, 0xEE);
}

PLIANT_AVX2_INLINE __m256 as_float(__m256i m) {
    return _mm256_castsi256_ps(m);
}
PLIANT_AVX2_INLINE __m256i as_int(__m256 m) {
    return _mm256_castps_si256(m);
}

// The 8 × 8 transpose: out[c] holds element c of rows[0 … 7].
PLIANT_AVX2_INLINE void transpose8(const __m256 rows[8], __m256 out[8]) {
    const __m256 t0 = _mm256_unpacklo_ps(rows[0], rows[1]);
    const __m256 t1 = _mm256_unpackhi_ps(rows[0], rows[1]);
    const __m256 t2 = _mm256_unpacklo_ps(rows[2], rows[3]);
    const __m256 t3 = _mm256_unpackhi_ps(rows[2], rows[3]);
    const __m256 t4 = _mm256_unpacklo_ps(rows[4], rows[5]);
    const __m256 t5 = _mm256_unpackhi_ps(rows[4], rows[5]);
    const __m256 t6 = _mm256_unpacklo_ps(rows[6], rows[7]);
    const __m256 t7 = _mm256_unpackhi_ps(rows[6], rows[7]);
    const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44);
    const __m256 u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
    const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44);
    const __m256 u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
    const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44);
    const __m256 u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
    const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44);
    const __m256 u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
    out[0] = _mm256_permute2f128_ps(u0, u4, 0x20);
    out[1] = _mm256_permute2f128_ps(u1, u5, 0x20);
    out[2] = _mm256_permute2f128_ps(u2, u6, 0x20);
    out[3] = _mm256_permute2f128_ps(u3, u7, 0x20);
    out[4] = _mm256_permute2f128_ps(u0, u4, 0x31);
    out[5] = _mm256_permute2f128_ps(u1, u5, 0x31);
    out[6] = _mm256_permute2f128_ps(u2, u6, 0x31);
    out[7] = _mm256_permute2f128_ps(u3, u7, 0x31);
}

// The grid's constants for locate() and trilinear reads of 8 lanes (from a RayCastKernel).
struct Grid8 {
    __m256 g_max[3];
    __m256i max_i0[3];
    __m256i stride_y, stride_z;
    std::int32_t dx, dy, dz;  // neighbour offsets in voxels
    const float* v;           // the values (4 floats per voxel for RGBA)
    const float* alpha;       // RGBA shaded: α per voxel
};

// The Grid8 of k's grid.
PLIANT_AVX2_INLINE void load_grid8(const RayCastKernel& k, Grid8& grid) {
    for (int a = 0; a < 3; ++a) {
        grid.g_max[a] = _mm256_set1_ps(k.g_max[a]);
        grid.max_i0[a] = _mm256_set1_epi32(k.max_i0[a]);
    }
    grid.stride_y = _mm256_set1_epi32(static_cast<std::int32_t>(k.stride[1]));
    grid.stride_z = _mm256_set1_epi32(static_cast<std::int32_t>(k.stride[2]));
    grid.dx = static_cast<std::int32_t>(k.d[0]);
    grid.dy = static_cast<std::int32_t>(k.d[1]);
    grid.dz = static_cast<std::int32_t>(k.d[2]);
    grid.v = k.values;
    grid.alpha = k.alpha;
}

// locate() along axis a: the clamp to [0, n − 1], the lower corner and the fraction.
PLIANT_AVX2_INLINE void locate_axis8(const Grid8& grid, int a, __m256 g, __m256i& corner,
                                     __m256& fraction) {
    const __m256 c = clamp8(g, _mm256_setzero_ps(), grid.g_max[a]);
    corner = _mm256_min_epi32(_mm256_cvttps_epi32(c), grid.max_i0[a]);
    fraction = _mm256_sub_ps(c, _mm256_cvtepi32_ps(corner));
}

// The voxel index of lower corners corner[].
PLIANT_AVX2_INLINE __m256i voxel_index8(const Grid8& grid, const __m256i corner[3]) {
    return _mm256_add_epi32(corner[0],
                            _mm256_add_epi32(_mm256_mullo_epi32(grid.stride_y, corner[1]),
                                             _mm256_mullo_epi32(grid.stride_z, corner[2])));
}

// locate(g) of 8 lanes: the voxel indices of the lower corners, and the fractions.
PLIANT_AVX2_INLINE __m256i locate8(const Grid8& grid, const __m256 g[3], __m256 fraction[3]) {
    __m256i corner[3];
    for (int a = 0; a < 3; ++a) {
        locate_axis8(grid, a, g[a], corner[a], fraction[a]);
    }
    return voxel_index8(grid, corner);
}

// lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz) of the x-lerps of the 4 rows of pairs, as
// interpolate_scalar() and interpolate_rgba() per channel.
PLIANT_AVX2_INLINE __m256 trilinear8(const __m256 first[4], const __m256 second[4],
                                     const __m256 fraction[3]) {
    const __m256 c00 = lerp8(first[0], second[0], fraction[0]);
    const __m256 c10 = lerp8(first[1], second[1], fraction[0]);
    const __m256 c01 = lerp8(first[2], second[2], fraction[0]);
    const __m256 c11 = lerp8(first[3], second[3], fraction[0]);
    return lerp8(lerp8(c00, c10, fraction[1]), lerp8(c01, c11, fraction[1]), fraction[2]);
}

// interpolate_rgba() of 8 lanes at voxel indices `at`: out[c] is channel c (α·r, α·g, α·b, α).
// A lane's x-adjacent voxel pair of a row is 8 consecutive floats: one load, then transposed.
PLIANT_AVX2_INLINE void interpolate_rgba8(const Grid8& grid, const std::int32_t* at,
                                          const __m256 fraction[3], __m256 out[4]) {
    const std::int32_t row[4] = {0, grid.dy, grid.dz, grid.dz + grid.dy};
    __m256 first[4][4], second[4][4];  // [channel][row]
    for (int r = 0; r < 4; ++r) {
        __m256 rows[LANES], t[LANES];
        for (int l = 0; l < LANES; ++l) {
            rows[l] = _mm256_loadu_ps(grid.v + 4 * static_cast<std::int64_t>(at[l] + row[r]));
        }
        transpose8(rows, t);
        for (int c = 0; c < 4; ++c) {
            first[c][r] = t[c];
            second[c][r] = t[4 + c];
        }
    }
    for (int c = 0; c < 4; ++c) {
        out[c] = trilinear8(first[c], second[c], fraction);
    }
}

// shade()'s factor from 8 central-difference gradients for rays along dir: 0.3 + 0.7 |n · dir|
// with n the normalized gradient; nonzero is where |gradient|² > 1e-30 (elsewhere shade() is 1).
PLIANT_AVX2_INLINE __m256 shade_factor8(const __m256 gradient[3], const __m256 dir[3],
                                        __m256& nonzero) {
    const __m256 len2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(gradient[0], gradient[0]),
                                                    _mm256_mul_ps(gradient[1], gradient[1])),
                                      _mm256_mul_ps(gradient[2], gradient[2]));
    const __m256 dot = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(gradient[0], dir[0]), _mm256_mul_ps(gradient[1], dir[1])),
        _mm256_mul_ps(gradient[2], dir[2]));
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7FFFFFFF));
    const __m256 cosine = _mm256_div_ps(_mm256_and_ps(dot, abs_mask), _mm256_sqrt_ps(len2));
    nonzero = _mm256_cmp_ps(len2, _mm256_set1_ps(1e-30f), _CMP_GT_OQ);
    return _mm256_add_ps(_mm256_set1_ps(0.3f), _mm256_mul_ps(_mm256_set1_ps(0.7f), cosine));
}

}  // namespace pliant::render::detail

#endif
