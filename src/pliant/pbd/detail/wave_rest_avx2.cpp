#include <algorithm>

#include "pliant/core/simd_dispatch.hpp"
#include "pliant/pbd/detail/wave_rest.hpp"

#if defined(PLIANT_HAS_AVX2_TARGET)
#include <immintrin.h>

#include "pliant/core/simd_avx2.hpp"
#endif

namespace pliant::pbd::detail {

#if defined(PLIANT_HAS_AVX2_TARGET)

namespace {

using simd::add;
using simd::mul;
using simd::sub;

// r and u of 8 consecutive vertices.
struct Displaced8 {
    __m256 rx, ry, rz, ux, uy, uz;
};

// r and u of vertices i .. i + 8 (the arrays hold 8 floats of padding after the last vertex).
PLIANT_AVX2_INLINE Displaced8 load8(const SoaDisplaced& p, std::int64_t i) {
    return {_mm256_loadu_ps(p.rx + i), _mm256_loadu_ps(p.ry + i), _mm256_loadu_ps(p.rz + i),
            _mm256_loadu_ps(p.ux + i), _mm256_loadu_ps(p.uy + i), _mm256_loadu_ps(p.uz + i)};
}

// displaced_difference, lane by lane.
struct Difference8 {
    __m256 x, y, z;
};
PLIANT_AVX2_INLINE Difference8 difference8(const Displaced8& a, const Displaced8& b) {
    return {add(sub(a.rx, b.rx), sub(a.ux, b.ux)), add(sub(a.ry, b.ry), sub(a.uy, b.uy)),
            add(sub(a.rz, b.rz), sub(a.uz, b.uz))};
}

// displaced_length and displaced_volume, lane by lane (functors, not lambdas: a lambda would not
// inherit the AVX2 target).
struct Length8 {
    PLIANT_AVX2_INLINE __m256 operator()(const Displaced8* v) const {
        const Difference8 d = difference8(v[0], v[1]);
        return _mm256_sqrt_ps(add(add(mul(d.x, d.x), mul(d.y, d.y)), mul(d.z, d.z)));
    }
};
struct Volume8 {
    PLIANT_AVX2_INLINE __m256 operator()(const Displaced8* v) const {
        const Difference8 e1 = difference8(v[1], v[0]);
        const Difference8 e2 = difference8(v[2], v[0]);
        const Difference8 e3 = difference8(v[3], v[0]);
        const __m256 cx = sub(mul(e2.y, e3.z), mul(e2.z, e3.y));
        const __m256 cy = sub(mul(e2.z, e3.x), mul(e2.x, e3.z));
        const __m256 cz = sub(mul(e2.x, e3.y), mul(e2.y, e3.x));
        return _mm256_div_ps(add(add(mul(e1.x, cx), mul(e1.y, cy)), mul(e1.z, cz)),
                             _mm256_set1_ps(6.0f));
    }
};

// The constraints of one run, from run.begin to end (colour-order indices), vertex m of
// constraint run.begin + k at solver index first[m] + k; each result into out[its index].
template <int K, typename Kernel>
PLIANT_AVX2_INLINE void run8(const SoaDisplaced& p, const LatticeRun& run, std::int64_t end,
                             float* out, const Kernel& kernel) {
    const std::int64_t count = end - run.begin;
    for (std::int64_t k = 0; k < count; k += 8) {
        Displaced8 v[K];
        for (int m = 0; m < K; ++m) {
            v[m] = load8(p, run.first[static_cast<std::size_t>(m)] + k);
        }
        const __m256 result = kernel(v);
        if (k + 8 <= count) {
            _mm256_storeu_ps(out + run.begin + k, result);
        } else {
            // The run's last count mod 8 (the other lanes computed from the padding or the
            // next vertices, not stored; a masked store is slow on some CPUs).
            float lanes[8];
            _mm256_storeu_ps(lanes, result);
            std::copy(lanes, lanes + (count - k), out + run.begin + k);
        }
    }
}

}  // namespace

PLIANT_AVX2_FN void displaced_lengths_runs_avx2(const SoaDisplaced& p, const LatticeRun* runs,
                                                std::int64_t r0, std::int64_t r1,
                                                std::int64_t num_runs, std::int64_t total,
                                                float* rest_lengths) {
    for (std::int64_t r = r0; r < r1; ++r) {
        const std::int64_t end = r + 1 < num_runs ? runs[r + 1].begin : total;
        run8<2>(p, runs[r], end, rest_lengths, Length8{});
    }
}

PLIANT_AVX2_FN void displaced_volumes_runs_avx2(const SoaDisplaced& p, const LatticeRun* runs,
                                                std::int64_t r0, std::int64_t r1,
                                                std::int64_t num_runs, std::int64_t total,
                                                float* rest_volumes) {
    for (std::int64_t r = r0; r < r1; ++r) {
        const std::int64_t end = r + 1 < num_runs ? runs[r + 1].begin : total;
        run8<4>(p, runs[r], end, rest_volumes, Volume8{});
    }
}

#else  // no AVX2 on this target
void displaced_lengths_runs_avx2(const SoaDisplaced&, const LatticeRun*, std::int64_t, std::int64_t,
                                 std::int64_t, std::int64_t, float*) {}
void displaced_volumes_runs_avx2(const SoaDisplaced&, const LatticeRun*, std::int64_t, std::int64_t,
                                 std::int64_t, std::int64_t, float*) {}
#endif

}  // namespace pliant::pbd::detail
