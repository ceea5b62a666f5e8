// begin_pixel() for 8 pixels of a row in AVX2, shared by the ray caster (raycast_avx2.cpp) and
// the mapped ray caster (mapped_raycast_avx2.cpp): pixel_ray(), clip_ray() and the segment count
// lane by lane in the scalar kernel's IEEE operations and order (raycast_kernel.hpp), so every
// lane's ray is bitwise the one begin_pixel() returns. PLIANT_AVX2_INLINE as in grid8_avx2.hpp.
#pragma once

#include <limits>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/grid8_avx2.hpp"
#include "pliant/render/detail/raycast_kernel.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

namespace pliant::render::detail {

// The rays of 8 pixels, lane l for pixel (x + l, y): PixelRay's fields (grid coordinates), the
// segment count N = max(1, ⌈length / Δs⌉), and the lanes whose rays hit the box with N < 2^30
// (bit l of hits) or with more (bit l of too_long, for the scalar code); other lanes miss.
struct Rays8 {
    __m256 dir[3], go[3], gd[3], inv_gd[3];
    __m256 t_near, t_far, margin, length;
    __m256i num_segments;
    int hits = 0;
    int too_long = 0;
};

PLIANT_AVX2_INLINE Rays8 begin_pixels8(const RayCastKernel& k, int x, int y) {
    Rays8 out;
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256 zero = _mm256_setzero_ps();
    const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    const __m256 inv_focal = _mm256_set1_ps(k.inv_focal);
    // pixel_ray(): (i + 0.5 − 0.5·width)·inv_focal, (0.5·height − (j + 0.5))·inv_focal.
    const __m256 fi = _mm256_cvtepi32_ps(
        _mm256_add_epi32(_mm256_set1_epi32(x), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7)));
    const __m256 cx = _mm256_mul_ps(
        _mm256_sub_ps(_mm256_add_ps(fi, half), _mm256_set1_ps(0.5f * static_cast<float>(k.width))),
        inv_focal);
    const __m256 cy =
        _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(0.5f * static_cast<float>(k.height)),
                                    _mm256_add_ps(_mm256_set1_ps(static_cast<float>(y)), half)),
                      inv_focal);
    __m256 origin[3];
    __m256* dir = out.dir;
    if (k.is_perspective) {
        __m256 v[3];
        for (int a = 0; a < 3; ++a) {
            v[a] = _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(k.forward[a]),
                                               _mm256_mul_ps(cx, _mm256_set1_ps(k.right[a]))),
                                 _mm256_mul_ps(cy, _mm256_set1_ps(k.up[a])));
        }
        const __m256 length = _mm256_sqrt_ps(
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(v[0], v[0]), _mm256_mul_ps(v[1], v[1])),
                          _mm256_mul_ps(v[2], v[2])));
        for (int a = 0; a < 3; ++a) {
            origin[a] = _mm256_set1_ps(k.eye[a]);
            dir[a] = _mm256_div_ps(v[a], length);
        }
    } else {
        for (int a = 0; a < 3; ++a) {
            origin[a] = _mm256_add_ps(_mm256_add_ps(_mm256_set1_ps(k.eye[a]),
                                                    _mm256_mul_ps(cx, _mm256_set1_ps(k.right[a]))),
                                      _mm256_mul_ps(cy, _mm256_set1_ps(k.up[a])));
            dir[a] = _mm256_set1_ps(k.forward[a]);
        }
    }
    // clip_ray(): the slab test per axis, then the clipping plane.
    __m256* go = out.go;
    __m256* gd = out.gd;
    __m256& t_near = out.t_near;
    __m256& t_far = out.t_far;
    t_near = zero;
    t_far = inf;
    __m256 miss = zero;
    for (int a = 0; a < 3; ++a) {
        const __m256 inv_spacing = _mm256_set1_ps(k.inv_spacing[a]);
        go[a] =
            _mm256_add_ps(_mm256_mul_ps(origin[a], inv_spacing), _mm256_set1_ps(k.grid_offset[a]));
        gd[a] = _mm256_mul_ps(dir[a], inv_spacing);
        const __m256 lo = _mm256_set1_ps(-0.5f);
        const __m256 hi = _mm256_set1_ps(static_cast<float>(k.n[a]) - 0.5f);
        const __m256 is_zero = _mm256_cmp_ps(gd[a], zero, _CMP_EQ_OQ);
        const __m256 outside = _mm256_or_ps(_mm256_cmp_ps(go[a], lo, _CMP_LT_OQ),
                                            _mm256_cmp_ps(go[a], hi, _CMP_GT_OQ));
        miss = _mm256_or_ps(miss, _mm256_and_ps(is_zero, outside));
        const __m256 inv =
            _mm256_blendv_ps(_mm256_div_ps(_mm256_set1_ps(1.0f), gd[a]), inf, is_zero);
        out.inv_gd[a] = inv;
        const __m256 t0 = _mm256_mul_ps(_mm256_sub_ps(lo, go[a]), inv);
        const __m256 t1 = _mm256_mul_ps(_mm256_sub_ps(hi, go[a]), inv);
        const __m256 swap = _mm256_cmp_ps(t0, t1, _CMP_GT_OQ);
        const __m256 t_lo = _mm256_blendv_ps(t0, t1, swap);
        const __m256 t_hi = _mm256_blendv_ps(t1, t0, swap);
        // std::max(t_near, t_lo) and std::min(t_far, t_hi), on the lanes with a non-zero component.
        t_near = _mm256_blendv_ps(_mm256_max_ps(t_lo, t_near), t_near, is_zero);
        t_far = _mm256_blendv_ps(_mm256_min_ps(t_hi, t_far), t_far, is_zero);
    }
    if (k.has_clip) {
        const __m256 n[3] = {_mm256_set1_ps(k.clip_normal.x), _mm256_set1_ps(k.clip_normal.y),
                             _mm256_set1_ps(k.clip_normal.z)};
        const __m256 a = _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(n[0], origin[0]),
                                                                   _mm256_mul_ps(n[1], origin[1])),
                                                     _mm256_mul_ps(n[2], origin[2])),
                                       _mm256_set1_ps(k.clip_offset));
        const __m256 s =
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(n[0], dir[0]), _mm256_mul_ps(n[1], dir[1])),
                          _mm256_mul_ps(n[2], dir[2]));
        const __m256 crossing = _mm256_div_ps(_mm256_xor_ps(a, _mm256_set1_ps(-0.0f)), s);
        const __m256 is_pos = _mm256_cmp_ps(s, zero, _CMP_GT_OQ);
        const __m256 is_neg = _mm256_cmp_ps(s, zero, _CMP_LT_OQ);
        t_near = _mm256_blendv_ps(t_near, _mm256_max_ps(crossing, t_near), is_pos);
        t_far = _mm256_blendv_ps(t_far, _mm256_min_ps(crossing, t_far), is_neg);
        const __m256 is_zero = _mm256_cmp_ps(s, zero, _CMP_EQ_OQ);
        miss = _mm256_or_ps(miss, _mm256_and_ps(is_zero, _mm256_cmp_ps(a, zero, _CMP_LT_OQ)));
    }
    const __m256 hit = _mm256_andnot_ps(miss, _mm256_cmp_ps(t_near, t_far, _CMP_LT_OQ));
    const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7FFFFFFF));
    const __m256 magnitude = _mm256_add_ps(
        _mm256_max_ps(_mm256_max_ps(_mm256_and_ps(go[0], abs_mask), _mm256_and_ps(go[1], abs_mask)),
                      _mm256_and_ps(go[2], abs_mask)),
        _mm256_mul_ps(t_far, _mm256_max_ps(_mm256_max_ps(_mm256_and_ps(gd[0], abs_mask),
                                                         _mm256_and_ps(gd[1], abs_mask)),
                                           _mm256_and_ps(gd[2], abs_mask))));
    out.margin = _mm256_add_ps(_mm256_set1_ps(SKIP_MARGIN),
                               _mm256_mul_ps(magnitude, _mm256_set1_ps(1.0f / 262144.0f)));
    // begin_pixel(): N = max(1, ⌈length / Δs⌉) segments.
    out.length = _mm256_sub_ps(t_far, t_near);
    const __m256 segments = _mm256_ceil_ps(_mm256_div_ps(out.length, _mm256_set1_ps(k.step)));
    const __m256 fits = _mm256_cmp_ps(segments, _mm256_set1_ps(1073741824.0f), _CMP_LT_OQ);
    out.num_segments =
        _mm256_max_epi32(_mm256_cvttps_epi32(_mm256_and_ps(segments, fits)), _mm256_set1_epi32(1));
    out.hits = _mm256_movemask_ps(_mm256_and_ps(hit, fits));
    out.too_long = _mm256_movemask_ps(_mm256_andnot_ps(fits, hit));
    return out;
}

}  // namespace pliant::render::detail

#endif
