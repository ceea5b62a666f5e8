// The 8-lane march bookkeeping shared by the ray caster (raycast_avx2.cpp) and the mapped ray
// caster (mapped_raycast_avx2.cpp): which lanes hold a ray, the empty-cube lookup, the jump past
// an empty cube and the front-to-back composite, each the scalar kernel's IEEE operations in the
// same order (raycast_kernel.hpp, mapped_raycast_kernel.hpp), so every lane stays bitwise the
// scalar march. PLIANT_AVX2_INLINE as in grid8_avx2.hpp.
#pragma once

#include <cstdint>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/grid8_avx2.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

namespace pliant::render::detail {

// The march state of 8 rays, one per lane (structure of arrays, reloaded every iteration: a lane
// is refilled by scalar stores), in grid coordinates.
struct alignas(32) Lanes {
    float dir[3][LANES];  // world direction (shading)
    float go[3][LANES];
    float gd[3][LANES];
    float inv_gd[3][LANES];
    float t_near[LANES], t_far[LANES], margin[LANES];
    float cr[LANES], cg[LANES], cb[LANES], acc[LANES];
    std::int32_t n[LANES], num_full[LANES], samples[LANES];
    // Offset of the lane's octant in the empty cubes (octant · cells), and of the up to 3 more
    // octants of a ray with zero direction components (the octant's own when there are fewer).
    std::int32_t cube[LANES];
    std::int32_t more[3][LANES];
};

// Lane l's more octants: those of `octant` flipped along some of the axes in the bit mask `zero`
// (the ray's zero direction components), up to 3, each at offset octant · num_cells.
inline void set_more_octants(Lanes& s, int l, int octant, int zero, std::int32_t num_cells) {
    int num_more = 0;
    for (int flip = 1; flip < 8; ++flip) {
        if ((flip & ~zero) == 0 && num_more < 3) {
            s.more[num_more++][l] = (octant ^ flip) * num_cells;
        }
    }
}

// An idle lane: a ray at the grid's corner that marches nothing (its loads stay in bounds).
inline void clear_lane(Lanes& s, int l) {
    for (int a = 0; a < 3; ++a) {
        s.dir[a][l] = 0.0f;
        s.go[a][l] = 0.0f;
        s.gd[a][l] = 1.0f;
        s.inv_gd[a][l] = 1.0f;
    }
    s.t_near[l] = s.t_far[l] = s.margin[l] = 0.0f;
    s.cr[l] = s.cg[l] = s.cb[l] = s.acc[l] = 0.0f;
    s.n[l] = s.num_full[l] = s.samples[l] = 0;
    s.cube[l] = 0;
    for (auto& m : s.more) {
        m[l] = 0;
    }
}

// Which of the 8 lanes hold a ray and which of those rays have zero direction components (their
// empty-cube lookups take up to 3 more octants), and the next entry of the queue of rays.
struct LaneSlots {
    int pixel_of[LANES] = {};  // the pixel of lane l's ray
    int num_live = 0;          // lanes with a ray
    int live_mask = 0;         // bit l: lane l has a ray
    int more_count = 0;        // live lanes whose rays have zero direction components
    int more_mask = 0;         // bit l: lane l's ray has zero direction components
    int next = 0;              // next entry of the queue

    // Lane l takes the ray of `pixel` (has_more: it has zero direction components).
    void take(int l, int pixel, bool has_more) {
        pixel_of[l] = pixel;
        live_mask |= 1 << l;
        ++num_live;
        more_mask = has_more ? more_mask | (1 << l) : more_mask & ~(1 << l);
        more_count += has_more ? 1 : 0;
    }
    // Lane l's ray ended or left the lane.
    void free(int l) {
        live_mask &= ~(1 << l);
        --num_live;
        if ((more_mask & (1 << l)) != 0) {
            more_mask &= ~(1 << l);
            --more_count;
        }
    }
};

// All ones in the lanes of bit mask `mask`.
PLIANT_AVX2_INLINE __m256i lanes_of8(int mask) {
    return _mm256_cmpgt_epi32(
        _mm256_and_si256(_mm256_set1_epi32(mask), _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128)),
        _mm256_setzero_si256());
}

// The empty-cube byte of cell `cell` for each lane (s.cube: the offset of the lane's octant in
// `cubes`), the largest with the up to 3 more octants (s.more, in more_cubes) when any live lane
// has them (`more`).
PLIANT_AVX2_INLINE __m256i cube_side8(const Lanes& s, const std::uint8_t* cubes,
                                      const std::uint8_t* more_cubes, __m256i cell, bool more) {
    alignas(32) std::int32_t at[LANES];
    store(at, _mm256_add_epi32(load(s.cube), cell));
    __m256i side = load_bytes(cubes, at);
    if (more) {
        for (const auto& m : s.more) {
            store(at, _mm256_add_epi32(load(m), cell));
            side = _mm256_max_epi32(side, load_bytes(more_cubes, at));
        }
    }
    return side;
}

// jump() / map_jump() for the lanes in `jumps` (empty cubes of `side` cells at cells q, a cell
// `size` grid units wide): the first sample past the cube's far planes (pulled in by the ray's
// margin); n_next for the others. A cell size 2^CELL_SHIFT gives jump()'s planes
// (q + side) << CELL_SHIFT bitwise: the integers convert exactly and the product is exact.
PLIANT_AVX2_INLINE __m256i jump8(const Lanes& s, const __m256i q[3], __m256i side, __m256 size,
                                 __m256i jumps, __m256i n_next, __m256i num_full, __m256 t_near,
                                 __m256 inv_step) {
    const __m256 zero = _mm256_setzero_ps();
    const __m256i one_i = _mm256_set1_epi32(1);
    __m256 t_exit = load(s.t_far);
    const __m256 margin = load(s.margin);
    for (int a = 0; a < 3; ++a) {
        const __m256 gd = load(s.gd[a]);
        const __m256 is_pos = _mm256_cmp_ps(gd, zero, _CMP_GT_OQ);
        const __m256 is_neg = _mm256_cmp_ps(gd, zero, _CMP_LT_OQ);
        const __m256 plane_pos = _mm256_sub_ps(
            _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(q[a], side)), size), margin);
        const __m256 plane_neg = _mm256_add_ps(
            _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_add_epi32(_mm256_sub_epi32(q[a], side), one_i)),
                          size),
            margin);
        const __m256 plane = _mm256_blendv_ps(plane_neg, plane_pos, is_pos);
        const __m256 candidate =
            _mm256_mul_ps(_mm256_sub_ps(plane, load(s.go[a])), load(s.inv_gd[a]));
        t_exit = _mm256_blendv_ps(t_exit, _mm256_min_ps(candidate, t_exit),
                                  _mm256_or_ps(is_pos, is_neg));
    }
    const __m256 x =
        _mm256_sub_ps(_mm256_mul_ps(_mm256_sub_ps(t_exit, t_near), inv_step), _mm256_set1_ps(0.5f));
    const __m256 past_end = _mm256_cmp_ps(x, _mm256_cvtepi32_ps(num_full), _CMP_NLT_UQ);
    __m256i n_end = _mm256_cvttps_epi32(x);
    // n_end += (float(n_end) < x): subtracting the all-ones mask adds 1.
    n_end =
        _mm256_sub_epi32(n_end, as_int(_mm256_cmp_ps(_mm256_cvtepi32_ps(n_end), x, _CMP_LT_OQ)));
    n_end = _mm256_and_si256(n_end, as_int(_mm256_cmp_ps(x, zero, _CMP_GT_OQ)));
    n_end = _mm256_max_epi32(n_end, n_next);
    n_end = as_int(_mm256_blendv_ps(as_float(n_end), as_float(num_full), past_end));
    return as_int(_mm256_blendv_ps(as_float(n_next), as_float(n_end), as_float(jumps)));
}

// composite(): front to back, the lanes in `blend` add straight colour rgba[0 … 2] with step
// opacity rgba[3] to s.cr, s.cg, s.cb, s.acc; the lanes in `classified` count a sample. Returns
// the blended lanes whose accumulated opacity exceeds `threshold`.
PLIANT_AVX2_INLINE __m256i composite8(Lanes& s, const __m256 rgba[4], __m256 blend,
                                      __m256i classified, __m256 threshold) {
    const __m256 acc = load(s.acc);
    const __m256 w = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(1.0f), acc), rgba[3]);
    const __m256 cr = load(s.cr);
    const __m256 cg = load(s.cg);
    const __m256 cb = load(s.cb);
    store(s.cr, _mm256_blendv_ps(cr, _mm256_add_ps(cr, _mm256_mul_ps(w, rgba[0])), blend));
    store(s.cg, _mm256_blendv_ps(cg, _mm256_add_ps(cg, _mm256_mul_ps(w, rgba[1])), blend));
    store(s.cb, _mm256_blendv_ps(cb, _mm256_add_ps(cb, _mm256_mul_ps(w, rgba[2])), blend));
    const __m256 acc_next = _mm256_blendv_ps(acc, _mm256_add_ps(acc, w), blend);
    store(s.acc, acc_next);
    store(s.samples, _mm256_sub_epi32(load(s.samples), classified));
    return as_int(_mm256_and_ps(blend, _mm256_cmp_ps(acc_next, threshold, _CMP_GT_OQ)));
}

}  // namespace pliant::render::detail

#endif
