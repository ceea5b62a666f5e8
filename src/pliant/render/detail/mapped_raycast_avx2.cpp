#include "pliant/render/detail/mapped_raycast_avx2.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/grid8_avx2.hpp"
#include "pliant/render/detail/lanes8_avx2.hpp"
#include "pliant/render/detail/ray_setup8_avx2.hpp"

namespace pliant::render::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

constexpr std::int64_t INDEX_LIMIT = std::int64_t{1} << 31;
// Rays with this many full samples or more are marched by the scalar kernel (int32 counters).
constexpr std::int64_t MAX_LANE_SAMPLES = std::int64_t{1} << 30;

// The march state of 8 rays (Lanes) and, per lane, the source coordinate of the lane's last
// classified sample and the index of the sample after it (−2: none), for the prefetch of the
// sample after next; the adaptive step's state (mapped_march()): the level the ray wants and
// its number of full samples (a run of 2^l segments needs that many left).
struct alignas(32) MapLanes : Lanes {
    float last_g[3][LANES];
    std::int32_t last_next[LANES];
    std::int32_t want[LANES];
    std::int32_t total[LANES];
};

// Puts ray p into lane l, marched over its samples [first, end) (visible_samples()); with the
// adaptive step (`levels` > 0) from the coarsest run that holds sample `first`, at that level
// (mapped_march()).
void fill_lane(const PixelRay& p, std::int32_t first, std::int32_t end, std::int32_t num_cells,
               int levels, MapLanes& s, int l) {
    for (int a = 0; a < 3; ++a) {
        s.dir[a][l] = p.dir[a];
        s.go[a][l] = p.r.go[a];
        s.gd[a][l] = p.r.gd[a];
        s.inv_gd[a][l] = p.r.inv_gd[a];
    }
    s.t_near[l] = p.r.t_near;
    s.t_far[l] = p.r.t_far;
    s.margin[l] = p.r.margin;
    s.cr[l] = s.cg[l] = s.cb[l] = s.acc[l] = 0.0f;
    s.n[l] = first & ~((std::int32_t{1} << levels) - 1);
    s.num_full[l] = end;
    s.samples[l] = 0;
    s.last_next[l] = -2;
    s.want[l] = levels;
    s.total[l] = static_cast<std::int32_t>(p.num_full);
    const int octant = octant_of(p.r);
    s.cube[l] = octant * num_cells;
    for (auto& m : s.more) {
        m[l] = s.cube[l];
    }
    set_more_octants(s, l, octant, zero_axes_of(p.r), num_cells);
}

// An idle lane (clear_lane()) with no classified sample.
void clear_map_lane(MapLanes& s, int l) {
    clear_lane(s, l);
    s.last_next[l] = -2;
    s.want[l] = 0;
    s.total[l] = 0;
}

// visible_samples() of 8 rays in floats (the span need only hold every sample of a visible
// cell, not be the scalar code's: float rounding of the slabs' coordinates stays far below
// VISIBLE_BOX_MARGIN and the sample of slack per side): into first and end; the whole
// [0, num_full) for a lane where a slab's parameters are NaN.
PLIANT_AVX2_INLINE void visible_samples8(const MappedKernel& m, const Rays8& rays, __m256i num_full,
                                         __m256i& first, __m256i& end) {
    const __m256 zero = _mm256_setzero_ps();
    __m256 t0 = rays.t_near;
    __m256 t1 = rays.t_far;
    __m256 unordered = zero;
    __m256 outside = zero;  // a ray parallel to a slab, outside it
    for (int k = 0; k < VISIBLE_SLABS; ++k) {
        __m256 o = zero, d = zero;
        for (int a = 0; a < 3; ++a) {
            if (SLAB_SIGNS[k][a] > 0) {
                o = _mm256_add_ps(o, rays.go[a]);
                d = _mm256_add_ps(d, rays.gd[a]);
            } else if (SLAB_SIGNS[k][a] < 0) {
                o = _mm256_sub_ps(o, rays.go[a]);
                d = _mm256_sub_ps(d, rays.gd[a]);
            }
        }
        const __m256 lo = _mm256_set1_ps(m.visible_lo[k]);
        const __m256 hi = _mm256_set1_ps(m.visible_hi[k]);
        const __m256 parallel = _mm256_cmp_ps(d, zero, _CMP_EQ_OQ);
        outside = _mm256_or_ps(
            outside, _mm256_and_ps(parallel, _mm256_or_ps(_mm256_cmp_ps(o, lo, _CMP_LT_OQ),
                                                          _mm256_cmp_ps(o, hi, _CMP_GT_OQ))));
        const __m256 ta = _mm256_div_ps(_mm256_sub_ps(lo, o), d);
        const __m256 tb = _mm256_div_ps(_mm256_sub_ps(hi, o), d);
        const __m256 use = _mm256_andnot_ps(parallel, _mm256_cmp_ps(ta, tb, _CMP_ORD_Q));
        unordered = _mm256_or_ps(unordered,
                                 _mm256_andnot_ps(parallel, _mm256_cmp_ps(ta, tb, _CMP_UNORD_Q)));
        t0 = _mm256_blendv_ps(t0, _mm256_max_ps(t0, _mm256_min_ps(ta, tb)), use);
        t1 = _mm256_blendv_ps(t1, _mm256_min_ps(t1, _mm256_max_ps(ta, tb)), use);
    }
    const __m256 inv_step = _mm256_set1_ps(m.target.inv_step);
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256 top = _mm256_cvtepi32_ps(num_full);
    const __m256 bottom = _mm256_set1_ps(-4.0f);
    // Samples before ⌊x0⌋ − 1 and from ⌊x1⌋ + 2 on lie outside (the clamps keep the
    // conversions in range; NaN lanes are replaced below).
    const __m256 x0 = _mm256_sub_ps(_mm256_mul_ps(_mm256_sub_ps(t0, rays.t_near), inv_step), half);
    const __m256 x1 = _mm256_sub_ps(_mm256_mul_ps(_mm256_sub_ps(t1, rays.t_near), inv_step), half);
    const __m256 c0 = _mm256_floor_ps(_mm256_min_ps(_mm256_max_ps(x0, bottom), top));
    const __m256 c1 = _mm256_floor_ps(_mm256_min_ps(_mm256_max_ps(x1, bottom), top));
    const __m256i zero_i = _mm256_setzero_si256();
    __m256i f =
        _mm256_max_epi32(_mm256_sub_epi32(_mm256_cvttps_epi32(c0), _mm256_set1_epi32(1)), zero_i);
    __m256i e =
        _mm256_min_epi32(_mm256_add_epi32(_mm256_cvttps_epi32(c1), _mm256_set1_epi32(2)), num_full);
    f = _mm256_min_epi32(f, num_full);
    e = _mm256_max_epi32(e, f);
    // A ray that misses the slabs (t0 > t1) or lies outside one: nothing; NaN: everything.
    const __m256 missing = _mm256_or_ps(outside, _mm256_cmp_ps(t0, t1, _CMP_GT_OQ));
    const __m256 whole = _mm256_or_ps(unordered, _mm256_or_ps(_mm256_cmp_ps(x0, x0, _CMP_UNORD_Q),
                                                              _mm256_cmp_ps(x1, x1, _CMP_UNORD_Q)));
    f = _mm256_blendv_epi8(f, num_full, as_int(missing));
    e = _mm256_blendv_epi8(e, num_full, as_int(missing));
    first = _mm256_blendv_epi8(f, zero_i, as_int(whole));
    end = _mm256_blendv_epi8(e, num_full, as_int(whole));
}

// begin_pixel() for the 8 pixels (x + l, y), l = 0 … 7 (begin_pixels8()), into out[l], and with
// skipping the span of each ray's samples that may lie in a visible cell (visible_samples8())
// into first[l], end[l] (else 0, num_full). Returns bit l set when lane l's ray hits the box with
// fewer than 2^30 segments (out[l] set), bit 8 + l when it hits with more (for the scalar code),
// neither when it misses.
PLIANT_AVX2_FN int setup_rays(const MappedKernel& m, int x, int y, PixelRay* out,
                              std::int32_t* first, std::int32_t* end) {
    const RayCastKernel& k = m.target;
    const Rays8 rays = begin_pixels8(k, x, y);
    const __m256i num_full = _mm256_sub_epi32(rays.num_segments, _mm256_set1_epi32(1));
    __m256i span_first = _mm256_setzero_si256();
    __m256i span_end = num_full;
    if (k.skipping) {
        visible_samples8(m, rays, num_full, span_first, span_end);
    }
    store(first, span_first);
    store(end, span_end);
    alignas(32) float v_dir[3][LANES], v_go[3][LANES], v_gd[3][LANES], inv_gd[3][LANES];
    alignas(32) float v_near[LANES], v_far[LANES], v_margin[LANES], v_length[LANES];
    alignas(32) std::int32_t v_segments[LANES];
    for (int a = 0; a < 3; ++a) {
        store(v_dir[a], rays.dir[a]);
        store(v_go[a], rays.go[a]);
        store(v_gd[a], rays.gd[a]);
        store(inv_gd[a], rays.inv_gd[a]);
    }
    store(v_near, rays.t_near);
    store(v_far, rays.t_far);
    store(v_margin, rays.margin);
    store(v_length, rays.length);
    store(v_segments, rays.num_segments);
    const int hits = rays.hits;
    for (int l = 0; l < LANES; ++l) {
        if ((hits >> l & 1) == 0) {
            continue;
        }
        PixelRay& p = out[l];
        for (int a = 0; a < 3; ++a) {
            p.dir[a] = v_dir[a][l];
            p.r.go[a] = v_go[a][l];
            p.r.gd[a] = v_gd[a][l];
            p.r.inv_gd[a] = inv_gd[a][l];
        }
        p.r.t_near = v_near[l];
        p.r.t_far = v_far[l];
        p.r.margin = v_margin[l];
        p.length = v_length[l];
        p.num_segments = v_segments[l];
        p.num_full = p.num_segments - 1;
    }
    return hits | (rays.too_long << LANES);
}

// A lane's stored gradient pair of a row, 2 voxels × 4 GradientValue from p: sign-extended to 8
// int32 (in float registers, for transpose8()).
PLIANT_AVX2_INLINE __m256 gradient_pair(const GradientValue* p) {
    static_assert(sizeof(GradientValue) == 2);
    return _mm256_castsi256_ps(
        _mm256_cvtepi16_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))));
}

// source_gradient() of 8 lanes located at voxel indices `at` with fractions `fraction`: out[a]
// the interpolated difference along source axis a. A lane's x-adjacent pair of a row is one
// 16-byte load, transposed, then converted to float (exact).
PLIANT_AVX2_INLINE void source_gradient8(const MappedKernel& m, const Grid8& src,
                                         const std::int32_t* at, const __m256 fraction[3],
                                         __m256 out[3]) {
    const std::int32_t row[4] = {0, src.dy, src.dz, src.dz + src.dy};
    __m256 first[3][4], second[3][4];  // [axis][row]
    for (int r = 0; r < 4; ++r) {
        __m256 rows[LANES], t[LANES];
        for (int l = 0; l < LANES; ++l) {
            rows[l] = gradient_pair(m.gradient + 4 * static_cast<std::int64_t>(at[l] + row[r]));
        }
        transpose8(rows, t);
        for (int a = 0; a < 3; ++a) {
            first[a][r] = _mm256_cvtepi32_ps(as_int(t[a]));
            second[a][r] = _mm256_cvtepi32_ps(as_int(t[4 + a]));
        }
    }
    for (int a = 0; a < 3; ++a) {
        out[a] = trilinear8(first[a], second[a], fraction);
    }
}

// interpolate_rgba8() of 8 lanes at voxel indices `at`: out[c] is channel c (α·r, α·g, α·b,
// α, in rgba8_voxel()'s units). A lane's x-adjacent voxel pair of a row is 8 consecutive bytes:
// one load, widened to int32, transposed, converted to float (exact) and premultiplied as
// rgba8_voxel().
PLIANT_AVX2_INLINE void interpolate_bytes8(const MappedKernel& m, const Grid8& grid,
                                           const std::int32_t* at, const __m256 fraction[3],
                                           __m256 out[4], __m256& max_alpha) {
    const std::int32_t row[4] = {0, grid.dy, grid.dz, grid.dz + grid.dy};
    __m256 first[4][4], second[4][4];  // [channel][row]
    for (int r = 0; r < 4; ++r) {
        __m256 rows[LANES], t[LANES];
        for (int l = 0; l < LANES; ++l) {
            const std::uint8_t* p = m.rgba8 + 4 * static_cast<std::int64_t>(at[l] + row[r]);
            rows[l] = as_float(
                _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
        }
        transpose8(rows, t);
        const __m256 a0 = _mm256_cvtepi32_ps(as_int(t[3]));
        const __m256 a1 = _mm256_cvtepi32_ps(as_int(t[7]));
        for (int c = 0; c < 3; ++c) {
            first[c][r] = _mm256_mul_ps(_mm256_cvtepi32_ps(as_int(t[c])), a0);
            second[c][r] = _mm256_mul_ps(_mm256_cvtepi32_ps(as_int(t[4 + c])), a1);
        }
        first[3][r] = a0;
        second[3][r] = a1;
    }
    for (int c = 0; c < 4; ++c) {
        out[c] = trilinear8(first[c], second[c], fraction);
    }
    max_alpha = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(first[3][0], second[3][0]),
                                            _mm256_max_ps(first[3][1], second[3][1])),
                              _mm256_max_ps(_mm256_max_ps(first[3][2], second[3][2]),
                                            _mm256_max_ps(first[3][3], second[3][3])));
}

// interpolate_bytes8() and source_gradient8() of 8 lanes of a packed source
// (PACKED_VOXEL_BYTES per voxel): a lane's x-adjacent voxel pair of a row is one 32-byte load
// that holds both voxels' bytes and gradients, transposed once; then the bytes' channels
// (shifts and masks, converted and premultiplied) as interpolate_bytes8() and the gradient's
// (sign-extended halves) as source_gradient8(), the same values; max_alpha the largest α byte
// of the 8 voxels, wide_alpha the largest of their neighbourhoods' (PACKED_WIDE_ALPHA).
PLIANT_AVX2_INLINE void interpolate_packed8(const MappedKernel& m, const Grid8& grid,
                                            const std::int32_t* at, const __m256 fraction[3],
                                            __m256 out[4], __m256 gradient[3], __m256& max_alpha,
                                            __m256& wide_alpha) {
    static_assert(PACKED_WIDE_ALPHA == 12);  // the 4th int32 of a record, alone in it
    const std::int32_t row[4] = {0, grid.dy, grid.dz, grid.dz + grid.dy};
    const __m256i byte = _mm256_set1_epi32(0xff);
    __m256 first[4][4], second[4][4];  // [channel][row]
    __m256 first_d[3][4], second_d[3][4];
    __m256i wide = _mm256_setzero_si256();
    for (int r = 0; r < 4; ++r) {
        __m256 rows[LANES], t[LANES];
        for (int l = 0; l < LANES; ++l) {
            rows[l] = _mm256_loadu_ps(reinterpret_cast<const float*>(
                m.rgba8 + PACKED_VOXEL_BYTES * static_cast<std::int64_t>(at[l] + row[r])));
        }
        transpose8(rows, t);
        for (std::int64_t x = 0; x < 2; ++x) {
            const __m256i v = as_int(t[4 * x]);
            const __m256 a = _mm256_cvtepi32_ps(_mm256_srli_epi32(v, 24));
            __m256(&corner)[4][4] = x == 0 ? first : second;
            corner[0][r] = _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_and_si256(v, byte)), a);
            corner[1][r] = _mm256_mul_ps(
                _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(v, 8), byte)), a);
            corner[2][r] = _mm256_mul_ps(
                _mm256_cvtepi32_ps(_mm256_and_si256(_mm256_srli_epi32(v, 16), byte)), a);
            corner[3][r] = a;
            const __m256i xy = as_int(t[4 * x + 1]);
            const __m256i z = as_int(t[4 * x + 2]);
            __m256(&d)[3][4] = x == 0 ? first_d : second_d;
            d[0][r] = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(xy, 16), 16));
            d[1][r] = _mm256_cvtepi32_ps(_mm256_srai_epi32(xy, 16));
            d[2][r] = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(z, 16), 16));
            wide = _mm256_max_epi32(wide, as_int(t[4 * x + 3]));
        }
    }
    wide_alpha = _mm256_cvtepi32_ps(wide);
    for (int c = 0; c < 4; ++c) {
        out[c] = trilinear8(first[c], second[c], fraction);
    }
    max_alpha = _mm256_max_ps(_mm256_max_ps(_mm256_max_ps(first[3][0], second[3][0]),
                                            _mm256_max_ps(first[3][1], second[3][1])),
                              _mm256_max_ps(_mm256_max_ps(first[3][2], second[3][2]),
                                            _mm256_max_ps(first[3][3], second[3][3])));
    for (int a = 0; a < 3; ++a) {
        gradient[a] = trilinear8(first_d[a], second_d[a], fraction);
    }
}

// mapped_classify<IS_RGBA>() of 8 samples in map cells q (fractions f) for rays along dir:
// out[0 … 2] the straight colour (shaded when SHADING), out[3] the step opacity (RGBA) or the
// lookup entry's, all 0 where the sample has no opacity (outside the source box, or none);
// max_alpha and wide_alpha as mapped_classify()'s (0 outside the source box). Lanes outside
// `mask` are sampled at source coordinate 0 (their loads stay in bounds; their results are not
// used).
template <bool IS_RGBA, bool SHADING>
PLIANT_AVX2_INLINE void classify8(const MappedKernel& m, const Grid8& src, const __m256i q[3],
                                  const __m256 f[3], __m256 mask, const __m256 dir8[3],
                                  __m256 out[4], __m256 source[3], __m256& max_alpha,
                                  __m256& wide_alpha) {
    const RayCastKernel& s = m.source;
    // 1. The map: the 8 nodes of each lane's cell, per channel, then the trilinear value and
    // (shading) its derivatives, as map_coordinate().
    alignas(32) std::int32_t qa[3][LANES];
    for (int a = 0; a < 3; ++a) {
        store(qa[a], q[a]);
    }
    // A lane's x-adjacent node pair of a row is 8 consecutive floats of the padded copy (4 per
    // node): one load per row, transposed.
    const std::int64_t row[4] = {0, m.node_stride[1], m.node_stride[2],
                                 m.node_stride[2] + m.node_stride[1]};
    std::int64_t first[LANES];
    for (int l = 0; l < LANES; ++l) {
        first[l] = qa[0][l] + m.node_stride[1] * qa[1][l] + m.node_stride[2] * qa[2][l];
    }
    __m256 node[4][8];  // [row][channel of the first node 0 … 3, of the second 4 … 7]
    for (int r = 0; r < 4; ++r) {
        __m256 rows[LANES];
        for (int l = 0; l < LANES; ++l) {
            rows[l] = _mm256_loadu_ps(m.nodes4 + 4 * (first[l] + row[r]));
        }
        transpose8(rows, node[r]);
    }
    __m256 g[3], jac[3][3];
    for (int ch = 0; ch < 3; ++ch) {
        const __m256 v[8] = {node[0][ch], node[0][4 + ch], node[1][ch], node[1][4 + ch],
                             node[2][ch], node[2][4 + ch], node[3][ch], node[3][4 + ch]};
        const __m256 e0 = lerp8(v[0], v[1], f[0]);
        const __m256 e1 = lerp8(v[2], v[3], f[0]);
        const __m256 e2 = lerp8(v[4], v[5], f[0]);
        const __m256 e3 = lerp8(v[6], v[7], f[0]);
        const __m256 y0 = lerp8(e0, e1, f[1]);
        const __m256 y1 = lerp8(e2, e3, f[1]);
        g[ch] = lerp8(y0, y1, f[2]);
        if constexpr (SHADING) {
            // B ∂g/∂t_a (map_coordinate()); lanes outside the mask may be NaN (not used).
            jac[0][ch] =
                lerp8(lerp8(_mm256_sub_ps(v[1], v[0]), _mm256_sub_ps(v[3], v[2]), f[1]),
                      lerp8(_mm256_sub_ps(v[5], v[4]), _mm256_sub_ps(v[7], v[6]), f[1]), f[2]);
            jac[1][ch] = lerp8(_mm256_sub_ps(e1, e0), _mm256_sub_ps(e3, e2), f[2]);
            jac[2][ch] = _mm256_sub_ps(y1, y0);
        }
    }
    // 2. In the source box (in_source()); lanes outside the mask at 0 (a cell without a valid map
    // interpolates NaN).
    __m256 inside = mask;
    for (int a = 0; a < 3; ++a) {
        inside = _mm256_and_ps(inside, _mm256_cmp_ps(g[a], _mm256_set1_ps(-0.5f), _CMP_GE_OQ));
        inside =
            _mm256_and_ps(inside, _mm256_cmp_ps(g[a], _mm256_set1_ps(m.source_hi[a]), _CMP_LE_OQ));
        g[a] = _mm256_and_ps(g[a], mask);
        source[a] = g[a];
    }
    // 3. classify<IS_RGBA>(s, locate(s, g)).
    __m256 fraction[3];
    alignas(32) std::int32_t at[LANES];
    store(at, locate8(src, g, fraction));
    // Shading: the stored gradient's rows are read here, beside the voxels' (not after the
    // classification, behind the branch on opacity): the loads of both overlap.
    __m256 d[3];
    const bool packed = IS_RGBA && SHADING && m.rgba8_stride == PACKED_VOXEL_BYTES;
    if (SHADING && !packed) {
        source_gradient8(m, src, at, fraction, d);
    }
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m256 zero = _mm256_setzero_ps();
    __m256 positive;
    max_alpha = _mm256_set1_ps(std::numeric_limits<float>::infinity());
    wide_alpha = max_alpha;
    if constexpr (IS_RGBA) {
        __m256 rgba[4];
        if (packed) {
            interpolate_packed8(m, src, at, fraction, rgba, d, max_alpha, wide_alpha);
        } else if (m.rgba8 != nullptr) {
            interpolate_bytes8(m, src, at, fraction, rgba, max_alpha);
        } else {
            interpolate_rgba8(src, at, fraction, rgba);
        }
        // rgba8: α and α·c in units of 1/255 and 1/255² (classify_rgba_source()).
        const bool bytes = m.rgba8 != nullptr;
        const __m256 a = clamp8(
            bytes ? _mm256_mul_ps(rgba[3], _mm256_set1_ps(1.0f / 255.0f)) : rgba[3], zero, one);
        positive = _mm256_and_ps(inside, _mm256_cmp_ps(a, zero, _CMP_GT_OQ));
        __m256 a_step;
        if (s.step_over_unit == 0.5f) {
            const __m256 half =
                _mm256_div_ps(a, _mm256_add_ps(one, _mm256_sqrt_ps(_mm256_sub_ps(one, a))));
            a_step = _mm256_blendv_ps(half, one, _mm256_cmp_ps(a, one, _CMP_GE_OQ));
        } else {
            alignas(32) float av[LANES];
            alignas(32) float st[LANES] = {};
            store(av, a);
            int todo = _mm256_movemask_ps(positive);
            while (todo != 0) {
                const int l = __builtin_ctz(static_cast<unsigned>(todo));
                todo &= todo - 1;
                st[l] = rgba_step_opacity(av[l], s.step_over_unit);
            }
            a_step = load(st);
        }
        const __m256 inv =
            _mm256_div_ps(one, bytes ? _mm256_mul_ps(rgba[3], _mm256_set1_ps(255.0f)) : rgba[3]);
        for (int ch = 0; ch < 3; ++ch) {
            out[ch] = _mm256_and_ps(positive, _mm256_mul_ps(rgba[ch], inv));
        }
        out[3] = _mm256_and_ps(positive, a_step);
    } else {
        // The trilinear lookup coordinate, then the lookup-table entry ⌊value + 0.5⌋.
        __m256 low[4], high[4];  // x-adjacent pairs of the 4 rows
        const std::int32_t voxel_row[4] = {0, src.dy, src.dz, src.dz + src.dy};
        for (int r = 0; r < 4; ++r) {
            load_pairs(src.v + voxel_row[r], at, low[r], high[r]);
        }
        const __m256 value = trilinear8(low, high, fraction);
        alignas(32) std::int32_t entry[LANES];
        store(entry, _mm256_slli_epi32(
                         _mm256_cvttps_epi32(_mm256_add_ps(value, _mm256_set1_ps(0.5f))), 2));
        __m256 e[4];
        load_entries(s.lut, entry, e);
        positive = _mm256_and_ps(inside, _mm256_cmp_ps(e[3], zero, _CMP_GT_OQ));
        for (int ch = 0; ch < 4; ++ch) {
            out[ch] = _mm256_and_ps(positive, e[ch]);
        }
    }
    max_alpha = _mm256_and_ps(max_alpha, inside);  // 0 outside the source box
    wide_alpha = _mm256_and_ps(wide_alpha, inside);
    const __m256 a_step = out[3];
    // 4. Shading (mapped_classify()): the stored source gradient at the sample through the map's
    // Jacobian (target_gradient()), for the samples with opacity.
    if constexpr (SHADING) {
        const __m256 shaded = _mm256_cmp_ps(a_step, zero, _CMP_GT_OQ);
        if (_mm256_movemask_ps(shaded) != 0) {
            __m256 gradient[3];
            for (int axis = 0; axis < 3; ++axis) {
                const __m256 dot = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(d[0], jac[axis][0]),
                                                               _mm256_mul_ps(d[1], jac[axis][1])),
                                                 _mm256_mul_ps(d[2], jac[axis][2]));
                gradient[axis] = _mm256_mul_ps(dot, _mm256_set1_ps(m.target.inv_spacing[axis]));
            }
            __m256 nonzero;
            const __m256 factor = shade_factor8(gradient, dir8, nonzero);
            const __m256 use = _mm256_and_ps(shaded, nonzero);
            for (int ch = 0; ch < 3; ++ch) {
                out[ch] = _mm256_blendv_ps(out[ch], _mm256_mul_ps(out[ch], factor), use);
            }
        }
    }
}

template <bool IS_RGBA, bool SHADING>
PLIANT_AVX2_FN std::int64_t mapped_tile(const MappedKernel& m, int x0, int y0, int x1, int y1,
                                        Color* colors) {
    const RayCastKernel& k = m.target;
    const int tile_width = x1 - x0;
    const auto num_cells =
        static_cast<std::int32_t>(static_cast<std::int64_t>(m.cells[0]) * m.cells[1] * m.cells[2]);
    std::int64_t samples = 0;

    // 1. The tile's rays; those with samples to march are queued for the lanes.
    PixelRay rays[TILE * TILE];
    std::int32_t queue[TILE * TILE];
    std::int32_t first[TILE * TILE], end[TILE * TILE];  // per pixel, visible_samples()
    int queue_size = 0;
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; x += LANES) {
            PixelRay group[LANES];
            alignas(32) std::int32_t group_first[LANES], group_end[LANES];
            const int bits = setup_rays(m, x, y, group, group_first, group_end);
            const int count = std::min(LANES, x1 - x);
            for (int l = 0; l < count; ++l) {
                const int pixel = (y - y0) * tile_width + (x + l - x0);
                PixelRay& p = rays[pixel];
                if ((bits >> l & 1) != 0) {
                    p = group[l];
                } else if ((bits >> (LANES + l) & 1) == 0 || !begin_pixel(k, x + l, y, p)) {
                    colors[pixel] = k.background;
                    continue;
                }
                std::int64_t span[2] = {0, p.num_full};
                if ((bits >> l & 1) != 0) {
                    span[0] = group_first[l];
                    span[1] = group_end[l];
                }
                if (span[0] >= span[1]) {  // no sample to march (or none in a visible cell)
                    colors[pixel] = mapped_end<IS_RGBA>(m, p, Accumulated{}, samples);
                } else if (p.num_full >= MAX_LANE_SAMPLES) {
                    const Accumulated c = mapped_march<IS_RGBA>(m, p, samples);
                    colors[pixel] = mapped_end<IS_RGBA>(m, p, c, samples);
                } else {
                    first[pixel] = static_cast<std::int32_t>(span[0]);
                    end[pixel] = static_cast<std::int32_t>(span[1]);
                    queue[queue_size++] = pixel;
                }
            }
        }
    }

    // 2. The queued rays in the 8 lanes, a lane taking the next ray as soon as its ray ends.
    const int levels = m.thin_levels;
    const bool adaptive = levels > 0;
    MapLanes s;
    LaneSlots slots;
    const auto end_lane = [&](int l) {
        std::int64_t lane_samples = s.samples[l];
        const Accumulated c{s.cr[l], s.cg[l], s.cb[l], s.acc[l]};
        colors[slots.pixel_of[l]] =
            mapped_end<IS_RGBA>(m, rays[slots.pixel_of[l]], c, lane_samples);
        samples += lane_samples;
    };
    const auto refill = [&](int l) {
        if (slots.next < queue_size) {
            const int pixel = queue[slots.next++];
            const PixelRay& p = rays[pixel];
            fill_lane(p, first[pixel], end[pixel], num_cells, levels, s, l);
            slots.take(l, pixel, zero_axes_of(p.r) != 0);
            return;
        }
        clear_map_lane(s, l);
    };
    const auto release = [&](int l) {
        slots.free(l);
        refill(l);
    };
    for (int l = 0; l < LANES; ++l) {
        refill(l);
    }

    const __m256 step = _mm256_set1_ps(k.step);
    const __m256 inv_step = _mm256_set1_ps(k.inv_step);
    const __m256 half = _mm256_set1_ps(0.5f);
    const __m256 zero = _mm256_setzero_ps();
    const __m256 threshold = _mm256_set1_ps(k.threshold);
    const __m256 b = _mm256_set1_ps(m.b);
    const __m256 inv_b = _mm256_set1_ps(m.inv_b);
    const __m256 half_b = _mm256_set1_ps(m.half_b);
    const __m256 g_max[3] = {_mm256_set1_ps(k.g_max[0]), _mm256_set1_ps(k.g_max[1]),
                             _mm256_set1_ps(k.g_max[2])};
    const __m256i last_cell[3] = {_mm256_set1_epi32(m.cells[0] - 1),
                                  _mm256_set1_epi32(m.cells[1] - 1),
                                  _mm256_set1_epi32(m.cells[2] - 1)};
    const __m256i cells_x = _mm256_set1_epi32(m.cells[0]);
    const __m256i cells_y = _mm256_set1_epi32(m.cells[1]);
    const __m256i one_i = _mm256_set1_epi32(1);
    const __m256 two = _mm256_set1_ps(2.0f);
    // The adaptive step (mapped_march()): the α byte limits of its levels, the runs of the
    // coarsest level (a jump lands on them), and the level a lane wants after a sample it did
    // not classify (skipped or without a valid map): the coarsest.
    __m256 thin_limit[MAX_THIN_LEVELS];
    for (int l = 0; l < levels; ++l) {
        thin_limit[l] = _mm256_set1_ps(m.thin_limit[l]);
    }
    const __m256i lattice_mask = _mm256_set1_epi32(~((std::int32_t{1} << levels) - 1));
    const __m256i levels_i = _mm256_set1_epi32(levels);
    Grid8 src;
    load_grid8(m.source, src);
    const std::uint8_t* cubes = m.empty_cube[0];

    // NOLINTNEXTLINE(bugprone-infinite-loop): the lambdas above retire lanes (num_live).
    while (slots.num_live > 0) {
        const __m256i live = lanes_of8(slots.live_mask);
        const __m256i n = load(s.n);
        const __m256i num_full = load(s.num_full);
        // The adaptive step: the run's level, level_at(): the number of levels l ≤ want whose
        // run of 2^l segments fits (both conditions hold for every level below one that holds).
        __m256i level = _mm256_setzero_si256();
        if (adaptive) {
            const __m256i want = load(s.want);
            const __m256i total = load(s.total);
            for (int l = 1; l <= levels; ++l) {
                const __m256i beyond =
                    _mm256_cmpgt_epi32(_mm256_add_epi32(n, _mm256_set1_epi32(1 << l)), total);
                level = _mm256_sub_epi32(
                    level, _mm256_andnot_si256(beyond,
                                               _mm256_cmpgt_epi32(want, _mm256_set1_epi32(l - 1))));
            }
        }
        const __m256i span = _mm256_sllv_epi32(one_i, level);
        // adaptive_position(): go + (t_near + (n + span / 2)·Δs)·gd; locate_map(): the clamp
        // to [0, n − 1], the map cell min(⌊t / B⌋, cells − 1) and the fraction.
        const __m256 t_near = load(s.t_near);
        const __m256 offset = _mm256_mul_ps(half, _mm256_cvtepi32_ps(span));
        const __m256 tm = _mm256_add_ps(
            t_near, _mm256_mul_ps(_mm256_add_ps(_mm256_cvtepi32_ps(n), offset), step));
        __m256i q[3];
        __m256 f[3];
        for (int a = 0; a < 3; ++a) {
            const __m256 g = _mm256_add_ps(load(s.go[a]), _mm256_mul_ps(tm, load(s.gd[a])));
            const __m256 x = _mm256_mul_ps(clamp8(g, zero, g_max[a]), inv_b);
            q[a] = _mm256_min_epi32(_mm256_cvttps_epi32(x), last_cell[a]);
            f[a] = _mm256_sub_ps(x, _mm256_cvtepi32_ps(q[a]));
        }
        const __m256i cell = _mm256_add_epi32(
            q[0],
            _mm256_mullo_epi32(cells_x, _mm256_add_epi32(q[1], _mm256_mullo_epi32(cells_y, q[2]))));
        __m256i n_next = _mm256_add_epi32(n, span);
        __m256i want_next = levels_i;
        __m256i classified;
        alignas(32) std::int32_t at[LANES];
        if (k.skipping) {
            // Lanes in an empty cube of cells jump past it (map_jump()); the others, in an empty
            // sub-cell (sub_cell_of(): s_a = f_a ≥ 1/2), past that sub-cell (sub_cell_jump()).
            const __m256i side = cube_side8(s, cubes, cubes, cell, slots.more_count > 0);
            const __m256i cube_jumps =
                _mm256_and_si256(live, _mm256_cmpgt_epi32(side, _mm256_setzero_si256()));
            __m256i sub[3];
            for (int a = 0; a < 3; ++a) {
                sub[a] = _mm256_and_si256(as_int(_mm256_cmp_ps(f[a], half, _CMP_GE_OQ)), one_i);
            }
            const __m256i bit = _mm256_or_si256(
                sub[0],
                _mm256_or_si256(_mm256_slli_epi32(sub[1], 1), _mm256_slli_epi32(sub[2], 2)));
            store(at, cell);
            const __m256i occupied = _mm256_cmpgt_epi32(
                _mm256_and_si256(_mm256_srlv_epi32(load_bytes(m.sub_occupied, at), bit), one_i),
                _mm256_setzero_si256());
            const __m256i sub_jumps =
                _mm256_andnot_si256(_mm256_or_si256(cube_jumps, occupied), live);
            const __m256i jumps = _mm256_or_si256(cube_jumps, sub_jumps);
            if (_mm256_movemask_ps(as_float(jumps)) != 0) {
                __m256i jump_q[3];
                for (int a = 0; a < 3; ++a) {
                    jump_q[a] = _mm256_blendv_epi8(
                        q[a], _mm256_add_epi32(_mm256_add_epi32(q[a], q[a]), sub[a]), sub_jumps);
                }
                const __m256i jump_side = _mm256_blendv_epi8(side, one_i, sub_jumps);
                const __m256 jump_size = _mm256_blendv_ps(b, half_b, as_float(sub_jumps));
                n_next = jump8(s, jump_q, jump_side, jump_size, jumps, n_next, num_full, t_near,
                               inv_step);
                if (adaptive) {
                    // thin_jump(): the runs of 2^levels from n + span, the last start at or
                    // before the sample past the region, at least n + span; from the span's end
                    // on, that sample.
                    const __m256i runs = _mm256_add_epi32(n, span);
                    const __m256i rounded = _mm256_add_epi32(
                        runs, _mm256_and_si256(lattice_mask, _mm256_sub_epi32(n_next, runs)));
                    const __m256i lattice = _mm256_max_epi32(rounded, runs);
                    const __m256i before_end =
                        _mm256_and_si256(jumps, _mm256_cmpgt_epi32(num_full, n_next));
                    n_next = _mm256_blendv_epi8(n_next, lattice, before_end);
                }
            }
            classified = _mm256_andnot_si256(jumps, live);
        } else {
            store(at, cell);
            const __m256i valid =
                _mm256_and_si256(load_bytes(m.occupancy, at), _mm256_set1_epi32(MAP_CELL_VALID));
            classified = _mm256_and_si256(live, _mm256_cmpgt_epi32(valid, _mm256_setzero_si256()));
            // Lanes without a valid map pass their run (n_next above).
        }
        __m256i terminated = _mm256_setzero_si256();
        if (_mm256_movemask_ps(as_float(classified)) != 0) {
            const __m256 dir8[3] = {load(s.dir[0]), load(s.dir[1]), load(s.dir[2])};
            __m256 rgba[4], g[3], max_alpha, wide_alpha;
            classify8<IS_RGBA, SHADING>(m, src, q, f, as_float(classified), dir8, rgba, g,
                                        max_alpha, wide_alpha);
            // The adaptive step: the sample wants the level its voxels allow (thin_level(), the
            // sum of its two conditions); below the run's own level it is discarded (the lane
            // marches its run again from n at that level); else it composites with the opacity
            // of its run (run_opacity()).
            __m256i composited = classified;
            if (adaptive) {
                static_assert(MAX_THIN_LEVELS == 2);
                __m256i allowed = as_int(_mm256_cmp_ps(max_alpha, thin_limit[0], _CMP_LT_OQ));
                if (levels >= 2) {
                    allowed = _mm256_add_epi32(
                        allowed, as_int(_mm256_cmp_ps(wide_alpha, thin_limit[1], _CMP_LT_OQ)));
                }
                allowed = _mm256_sub_epi32(_mm256_setzero_si256(), allowed);
                const __m256i discarded =
                    _mm256_and_si256(classified, _mm256_cmpgt_epi32(level, allowed));
                composited = _mm256_andnot_si256(discarded, classified);
                for (int l = 1; l <= levels; ++l) {
                    const __m256i longer = _mm256_cmpgt_epi32(level, _mm256_set1_epi32(l - 1));
                    rgba[3] = _mm256_blendv_ps(rgba[3],
                                               _mm256_mul_ps(rgba[3], _mm256_sub_ps(two, rgba[3])),
                                               as_float(longer));
                }
                n_next = _mm256_blendv_epi8(n_next, n, discarded);
                want_next = _mm256_blendv_epi8(want_next, allowed, classified);
            }
            // Prefetch: the voxel rows of the sample after next, extrapolated from this sample's
            // source coordinate and the last one's when they are consecutive samples (this one
            // the sample after the last).
            const __m256i consecutive =
                _mm256_and_si256(classified, _mm256_cmpeq_epi32(load(s.last_next), n));
            int ahead_mask = _mm256_movemask_ps(as_float(consecutive));
            if (ahead_mask != 0) {
                __m256i corner[3];
                for (int a = 0; a < 3; ++a) {
                    const __m256 ahead =
                        _mm256_add_ps(g[a], _mm256_mul_ps(_mm256_set1_ps(2.0f),
                                                          _mm256_sub_ps(g[a], load(s.last_g[a]))));
                    __m256 unused;
                    locate_axis8(src, a, ahead, corner[a], unused);
                }
                alignas(32) std::int32_t index[LANES];
                store(index, voxel_index8(src, corner));
                constexpr std::int64_t CH = IS_RGBA ? 4 : 1;  // floats per voxel
                const std::int64_t dy = CH * std::int64_t{src.dy};
                const std::int64_t dz = CH * std::int64_t{src.dz};
                // The voxels' first bytes: the floats', or the rgba8 source's (4 per voxel, or
                // the packed records, gradient included).
                const auto* bytes = m.rgba8 != nullptr ? reinterpret_cast<const char*>(m.rgba8)
                                                       : reinterpret_cast<const char*>(src.v);
                const bool packed = IS_RGBA && SHADING && m.rgba8_stride == PACKED_VOXEL_BYTES;
                const std::int64_t size =
                    m.rgba8 != nullptr ? m.rgba8_stride / CH : std::int64_t{sizeof(float)};
                const std::int64_t by = size * dy, bz = size * dz;
                while (ahead_mask != 0) {
                    const int l = __builtin_ctz(static_cast<unsigned>(ahead_mask));
                    ahead_mask &= ahead_mask - 1;
                    const char* v = bytes + size * CH * static_cast<std::int64_t>(index[l]);
                    _mm_prefetch(v, _MM_HINT_T0);
                    _mm_prefetch(v + by, _MM_HINT_T0);
                    _mm_prefetch(v + bz, _MM_HINT_T0);
                    _mm_prefetch(v + bz + by, _MM_HINT_T0);
                    if (SHADING && !packed) {
                        // The stored gradient's rows of that voxel, 4 values per voxel.
                        const GradientValue* d =
                            m.gradient + 4 * static_cast<std::int64_t>(index[l]);
                        const std::int64_t gy = 4 * std::int64_t{src.dy};
                        const std::int64_t gz = 4 * std::int64_t{src.dz};
                        _mm_prefetch(reinterpret_cast<const char*>(d), _MM_HINT_T0);
                        _mm_prefetch(reinterpret_cast<const char*>(d + gy), _MM_HINT_T0);
                        _mm_prefetch(reinterpret_cast<const char*>(d + gz), _MM_HINT_T0);
                        _mm_prefetch(reinterpret_cast<const char*>(d + gz + gy), _MM_HINT_T0);
                    }
                }
            }
            for (int a = 0; a < 3; ++a) {
                store(s.last_g[a], _mm256_blendv_ps(load(s.last_g[a]), g[a], as_float(classified)));
            }
            store(s.last_next,
                  _mm256_blendv_epi8(load(s.last_next),
                                     _mm256_blendv_epi8(_mm256_set1_epi32(-2), n_next, composited),
                                     classified));
            // composite(): front to back, the samples with opacity.
            const __m256 blend =
                _mm256_and_ps(as_float(composited), _mm256_cmp_ps(rgba[3], zero, _CMP_GT_OQ));
            terminated = composite8(s, rgba, blend, classified, threshold);
        }
        store(s.n, n_next);
        store(s.want, want_next);
        // Done: opaque (accumulated opacity above the threshold), or no sample left.
        const __m256i more_to_march = _mm256_cmpgt_epi32(num_full, n_next);
        const __m256i done =
            _mm256_andnot_si256(_mm256_andnot_si256(terminated, more_to_march), live);
        int done_mask = _mm256_movemask_ps(as_float(done));
        while (done_mask != 0) {
            const int l = __builtin_ctz(static_cast<unsigned>(done_mask));
            done_mask &= done_mask - 1;
            end_lane(l);
            release(l);
        }
    }
    return samples;
}

}  // namespace

bool mapped_avx2_fits(const MappedKernel& m) {
    const RayCastKernel& s = m.source;
    const std::int64_t voxels = static_cast<std::int64_t>(s.n[0]) * s.n[1] * s.n[2];
    const std::int64_t num_cells = static_cast<std::int64_t>(m.cells[0]) * m.cells[1] * m.cells[2];
    for (int o = 0; o < 8; ++o) {
        if (m.empty_cube[o] != m.empty_cube[0] + o * num_cells) {
            return false;
        }
    }
    const std::int64_t floats_per_voxel = s.is_rgba ? 4 : 1;
    return has_avx2() && (s.is_rgba || s.lut != nullptr) && s.d[0] == 1 &&
           floats_per_voxel * voxels < INDEX_LIMIT / 2 && 8 * num_cells < INDEX_LIMIT &&
           (!m.target.shading || m.gradient != nullptr);
}

PLIANT_AVX2_FN std::int64_t mapped_tile_avx2(const MappedKernel& m, int x0, int y0, int x1, int y1,
                                             Color* colors) {
    if (m.source.is_rgba) {
        return m.target.shading ? mapped_tile<true, true>(m, x0, y0, x1, y1, colors)
                                : mapped_tile<true, false>(m, x0, y0, x1, y1, colors);
    }
    return m.target.shading ? mapped_tile<false, true>(m, x0, y0, x1, y1, colors)
                            : mapped_tile<false, false>(m, x0, y0, x1, y1, colors);
}

#else

bool mapped_avx2_fits(const MappedKernel&) {
    return false;
}

std::int64_t mapped_tile_avx2(const MappedKernel&, int, int, int, int, Color*) {
    return 0;
}

#endif

}  // namespace pliant::render::detail
