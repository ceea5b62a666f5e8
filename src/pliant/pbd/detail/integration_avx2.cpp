#include "pliant/pbd/detail/integration_avx2.hpp"

#include "pliant/core/simd_dispatch.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

#include "pliant/core/simd_avx2.hpp"
#endif

namespace pliant::pbd::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

// One vertex, as integration.cpp's update_velocities_and_predict.
PLIANT_AVX2_INLINE void finish_one(const SoaMotion& a, std::int64_t i, const SubstepMotion& m) {
    Float4 q{a.p.x[i], a.p.y[i], a.p.z[i], a.p.w[i]};
    Vec3f previous{a.previous_x[i], a.previous_y[i], a.previous_z[i]};
    Vec3f vel = a.pinned[i] != 0 ? Vec3f{} : substep_velocity(q, previous, m);
    predict_vertex(q, previous, vel, a.inv_masses[i], m);
    a.p.x[i] = q.x;
    a.p.y[i] = q.y;
    a.p.z[i] = q.z;
    a.p.w[i] = q.w;
    a.previous_x[i] = previous.x;
    a.previous_y[i] = previous.y;
    a.previous_z[i] = previous.z;
}

}  // namespace

PLIANT_AVX2_FN void finish_substep_soa_avx2(const SoaMotion& a, std::int64_t begin,
                                            std::int64_t end, const SubstepMotion& m) {
    using simd::add;
    using simd::mul;
    using simd::sub;
    const __m256 zero = _mm256_setzero_ps();
    const __m256 h = _mm256_set1_ps(m.h);
    const __m256 inv_h = _mm256_set1_ps(m.inv_h);
    const __m256 keep = _mm256_set1_ps(m.keep);
    const __m256 gx = _mm256_set1_ps(m.gravity_h.x);
    const __m256 gy = _mm256_set1_ps(m.gravity_h.y);
    const __m256 gz = _mm256_set1_ps(m.gravity_h.z);
    std::int64_t i = begin;
    for (; i + 8 <= end; i += 8) {
        const __m256 x = _mm256_loadu_ps(a.p.x + i);
        const __m256 y = _mm256_loadu_ps(a.p.y + i);
        const __m256 z = _mm256_loadu_ps(a.p.z + i);
        const __m256 w = _mm256_loadu_ps(a.inv_masses + i);
        // Free (not pinned) lanes: all ones.
        const __m128i pinned8 = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(a.pinned + i));
        const __m256 free = _mm256_castsi256_ps(
            _mm256_cmpeq_epi32(_mm256_cvtepu8_epi32(pinned8), _mm256_setzero_si256()));
        // substep_velocity: ((p − previous) · inv_h) · keep, 0 when pinned.
        const __m256 vx =
            _mm256_and_ps(free, mul(mul(sub(x, _mm256_loadu_ps(a.previous_x + i)), inv_h), keep));
        const __m256 vy =
            _mm256_and_ps(free, mul(mul(sub(y, _mm256_loadu_ps(a.previous_y + i)), inv_h), keep));
        const __m256 vz =
            _mm256_and_ps(free, mul(mul(sub(z, _mm256_loadu_ps(a.previous_z + i)), inv_h), keep));
        // predict_vertex: previous = p; w > 0: p += h (v + g h), p.w = w; else p kept, p.w = 0.
        _mm256_storeu_ps(a.previous_x + i, x);
        _mm256_storeu_ps(a.previous_y + i, y);
        _mm256_storeu_ps(a.previous_z + i, z);
        const __m256 moves = _mm256_cmp_ps(w, zero, _CMP_GT_OQ);
        _mm256_storeu_ps(a.p.x + i, _mm256_blendv_ps(x, add(x, mul(h, add(vx, gx))), moves));
        _mm256_storeu_ps(a.p.y + i, _mm256_blendv_ps(y, add(y, mul(h, add(vy, gy))), moves));
        _mm256_storeu_ps(a.p.z + i, _mm256_blendv_ps(z, add(z, mul(h, add(vz, gz))), moves));
        _mm256_storeu_ps(a.p.w + i, _mm256_and_ps(moves, w));
    }
    for (; i < end; ++i) {
        finish_one(a, i, m);
    }
}

#else  // no AVX2 on this target
void finish_substep_soa_avx2(const SoaMotion&, std::int64_t, std::int64_t, const SubstepMotion&) {}
#endif

}  // namespace pliant::pbd::detail
