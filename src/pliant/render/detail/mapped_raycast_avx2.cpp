#include "pliant/render/detail/mapped_raycast_avx2.hpp"

#include <cstdint>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/render/detail/grid8_avx2.hpp"

namespace pliant::render::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

// The α trilinear of mapped_shading_value<true>() at g, 8 lanes.
PLIANT_AVX2_INLINE __m256 alpha8(const Grid8& s, const __m256 g[3]) {
    __m256 fraction[3];
    alignas(32) std::int32_t at[LANES];
    _mm256_store_si256(reinterpret_cast<__m256i*>(at), locate8(s, g, fraction));
    const std::int32_t row[4] = {0, s.dy, s.dz, s.dz + s.dy};
    __m256 first[4], second[4];
    for (int r = 0; r < 4; ++r) {
        alignas(32) float a[LANES], b[LANES];
        for (int l = 0; l < LANES; ++l) {
            const float* p = s.alpha + at[l] + row[r];
            a[l] = p[0];
            b[l] = p[s.dx];
        }
        first[r] = _mm256_load_ps(a);
        second[r] = _mm256_load_ps(b);
    }
    return trilinear8(first, second, fraction);
}

}  // namespace

bool mapped_avx2_fits(const MappedKernel& m) {
    const RayCastKernel& s = m.source;
    const std::int64_t voxels = static_cast<std::int64_t>(s.n[0]) * s.n[1] * s.n[2];
    return has_avx2() && s.is_rgba && s.n[0] >= 2 && 4 * voxels < (std::int64_t{1} << 31) &&
           (!m.target.shading || s.alpha != nullptr);
}

PLIANT_AVX2_FN void mapped_classify_avx2(const MappedKernel& m, const MapCell* cells, int count,
                                         Vec3f dir, Sample* out) {
    const RayCastKernel& s = m.source;
    // Lanes past count repeat the first cell (their results are dropped).
    MapCell c[LANES];
    for (int l = 0; l < LANES; ++l) {
        c[l] = cells[l < count ? l : 0];
    }
    // 1. The map: the 8 nodes of each lane's cell, per channel, then the trilinear value and
    // (shading) its derivatives, as map_coordinate().
    const std::int64_t dx = 3, dy = 3 * m.node_stride[1], dz = 3 * m.node_stride[2];
    const std::int64_t off[8] = {0, dx, dy, dy + dx, dz, dz + dx, dz + dy, dz + dy + dx};
    const float* p[LANES];
    alignas(32) float fx[LANES], fy[LANES], fz[LANES];
    for (int l = 0; l < LANES; ++l) {
        p[l] =
            m.nodes + 3 * (c[l].q[0] + m.node_stride[1] * c[l].q[1] + m.node_stride[2] * c[l].q[2]);
        fx[l] = c[l].f[0];
        fy[l] = c[l].f[1];
        fz[l] = c[l].f[2];
    }
    const __m256 f0 = _mm256_load_ps(fx), f1 = _mm256_load_ps(fy), f2 = _mm256_load_ps(fz);
    const __m256 inv_b = _mm256_set1_ps(m.inv_b);
    __m256 g[3], jac[3][3];
    for (int ch = 0; ch < 3; ++ch) {
        __m256 v[8];
        for (int i = 0; i < 8; ++i) {
            const std::int64_t o = off[i] + ch;
            v[i] = _mm256_setr_ps(p[0][o], p[1][o], p[2][o], p[3][o], p[4][o], p[5][o], p[6][o],
                                  p[7][o]);
        }
        const __m256 e0 = lerp8(v[0], v[1], f0);
        const __m256 e1 = lerp8(v[2], v[3], f0);
        const __m256 e2 = lerp8(v[4], v[5], f0);
        const __m256 e3 = lerp8(v[6], v[7], f0);
        const __m256 y0 = lerp8(e0, e1, f1);
        const __m256 y1 = lerp8(e2, e3, f1);
        g[ch] = lerp8(y0, y1, f2);
        if (m.target.shading) {
            jac[0][ch] = _mm256_mul_ps(
                lerp8(lerp8(_mm256_sub_ps(v[1], v[0]), _mm256_sub_ps(v[3], v[2]), f1),
                      lerp8(_mm256_sub_ps(v[5], v[4]), _mm256_sub_ps(v[7], v[6]), f1), f2),
                inv_b);
            jac[1][ch] =
                _mm256_mul_ps(lerp8(_mm256_sub_ps(e1, e0), _mm256_sub_ps(e3, e2), f2), inv_b);
            jac[2][ch] = _mm256_mul_ps(_mm256_sub_ps(y1, y0), inv_b);
        }
    }
    // 2. In the source box (in_source()).
    __m256 inside = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    for (int a = 0; a < 3; ++a) {
        inside = _mm256_and_ps(inside, _mm256_cmp_ps(g[a], _mm256_set1_ps(-0.5f), _CMP_GE_OQ));
        inside =
            _mm256_and_ps(inside, _mm256_cmp_ps(g[a], _mm256_set1_ps(m.source_hi[a]), _CMP_LE_OQ));
    }
    // 3. classify<true>(s, locate(s, g)).
    Grid8 src;
    load_grid8(s, src);
    __m256 fraction[3];
    alignas(32) std::int32_t at[LANES];
    _mm256_store_si256(reinterpret_cast<__m256i*>(at), locate8(src, g, fraction));
    __m256 rgba[4];
    interpolate_rgba8(src, at, fraction, rgba);
    const __m256 one = _mm256_set1_ps(1.0f);
    const __m256 a = clamp8(rgba[3], _mm256_setzero_ps(), one);
    const __m256 positive =
        _mm256_and_ps(inside, _mm256_cmp_ps(a, _mm256_setzero_ps(), _CMP_GT_OQ));
    __m256 a_step;
    if (s.step_over_unit == 0.5f) {
        const __m256 half =
            _mm256_div_ps(a, _mm256_add_ps(one, _mm256_sqrt_ps(_mm256_sub_ps(one, a))));
        a_step = _mm256_blendv_ps(half, one, _mm256_cmp_ps(a, one, _CMP_GE_OQ));
    } else {
        alignas(32) float av[LANES], st[LANES];
        _mm256_store_ps(av, a);
        for (int l = 0; l < LANES; ++l) {
            st[l] = av[l] > 0.0f ? rgba_step_opacity(av[l], s.step_over_unit) : 0.0f;
        }
        a_step = _mm256_load_ps(st);
    }
    const __m256 inv = _mm256_div_ps(one, rgba[3]);
    __m256 color[3];
    for (int ch = 0; ch < 3; ++ch) {
        color[ch] = _mm256_mul_ps(rgba[ch], inv);
    }
    // 4. Shading (mapped_classify()): central differences through the map's Jacobian.
    const __m256 shaded =
        _mm256_and_ps(positive, _mm256_cmp_ps(a_step, _mm256_setzero_ps(), _CMP_GT_OQ));
    if (m.target.shading && _mm256_movemask_ps(shaded) != 0) {
        __m256 gradient[3];
        for (int axis = 0; axis < 3; ++axis) {
            __m256 gp[3], gm[3];
            for (int ch = 0; ch < 3; ++ch) {
                gp[ch] = _mm256_add_ps(g[ch], jac[axis][ch]);
                gm[ch] = _mm256_sub_ps(g[ch], jac[axis][ch]);
            }
            gradient[axis] = _mm256_mul_ps(_mm256_sub_ps(alpha8(src, gp), alpha8(src, gm)),
                                           _mm256_set1_ps(m.target.inv_spacing[axis]));
        }
        const __m256 dir8[3] = {_mm256_set1_ps(dir.x), _mm256_set1_ps(dir.y),
                                _mm256_set1_ps(dir.z)};
        __m256 nonzero;
        const __m256 f = shade_factor8(gradient, dir8, nonzero);
        const __m256 use = _mm256_and_ps(shaded, nonzero);
        for (__m256& ch : color) {
            ch = _mm256_blendv_ps(ch, _mm256_mul_ps(ch, f), use);
        }
    }
    alignas(32) float r[LANES], gg[LANES], b[LANES], al[LANES], ok[LANES];
    _mm256_store_ps(r, color[0]);
    _mm256_store_ps(gg, color[1]);
    _mm256_store_ps(b, color[2]);
    _mm256_store_ps(al, a_step);
    _mm256_store_ps(ok, positive);
    for (int l = 0; l < count; ++l) {
        // ok: all bits set (a NaN, != 0) where the sample has opacity, else +0.
        out[l] = ok[l] != 0.0f ? Sample{r[l], gg[l], b[l], al[l]} : Sample{0.0f, 0.0f, 0.0f, 0.0f};
    }
}

#else

bool mapped_avx2_fits(const MappedKernel&) {
    return false;
}

void mapped_classify_avx2(const MappedKernel& m, const MapCell* cells, int count, Vec3f dir,
                          Sample* out) {
    ScalarBatch<true>{}(m, cells, count, dir, out);
}

#endif

}  // namespace pliant::render::detail
