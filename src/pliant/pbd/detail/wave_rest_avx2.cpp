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

// r and u of 8 consecutive vertices (u only along the displaced axes, AXES as in wave_rest.hpp).
struct Displaced8 {
    __m256 r[3];
    __m256 u[3];
};

// r and u of vertices i .. i + 8 (the arrays hold 8 floats of padding after the last vertex).
template <int AXES>
PLIANT_AVX2_INLINE Displaced8 load8(const SoaDisplaced& p, std::int64_t i) {
    const float* r[3] = {p.rx, p.ry, p.rz};
    const float* u[3] = {p.ux, p.uy, p.uz};
    Displaced8 out{};
    for (int c = 0; c < 3; ++c) {
        out.r[c] = _mm256_loadu_ps(r[c] + i);
        if ((AXES >> c & 1) != 0) {
            out.u[c] = _mm256_loadu_ps(u[c] + i);
        }
    }
    return out;
}

// displaced_difference, lane by lane.
struct Difference8 {
    __m256 x, y, z;
};
template <int AXES>
PLIANT_AVX2_INLINE __m256 component8(const Displaced8& a, const Displaced8& b, int c) {
    const __m256 d = sub(a.r[c], b.r[c]);
    return (AXES >> c & 1) != 0 ? add(d, sub(a.u[c], b.u[c])) : d;
}
template <int AXES>
PLIANT_AVX2_INLINE Difference8 difference8(const Displaced8& a, const Displaced8& b) {
    return {component8<AXES>(a, b, 0), component8<AXES>(a, b, 1), component8<AXES>(a, b, 2)};
}

// displaced_length and displaced_volume, lane by lane (functors, not lambdas: a lambda would not
// inherit the AVX2 target).
template <int AXES>
struct Length8 {
    PLIANT_AVX2_INLINE __m256 operator()(const Displaced8* v) const {
        const Difference8 d = difference8<AXES>(v[0], v[1]);
        return _mm256_sqrt_ps(add(add(mul(d.x, d.x), mul(d.y, d.y)), mul(d.z, d.z)));
    }
};
template <int AXES>
struct Volume8 {
    PLIANT_AVX2_INLINE __m256 operator()(const Displaced8* v) const {
        const Difference8 e1 = difference8<AXES>(v[1], v[0]);
        const Difference8 e2 = difference8<AXES>(v[2], v[0]);
        const Difference8 e3 = difference8<AXES>(v[3], v[0]);
        const __m256 cx = sub(mul(e2.y, e3.z), mul(e2.z, e3.y));
        const __m256 cy = sub(mul(e2.z, e3.x), mul(e2.x, e3.z));
        const __m256 cz = sub(mul(e2.x, e3.y), mul(e2.y, e3.x));
        return _mm256_div_ps(add(add(mul(e1.x, cx), mul(e1.y, cy)), mul(e1.z, cz)),
                             _mm256_set1_ps(6.0f));
    }
};

// The constraints of runs [r0, r1), run r from runs[r].begin to the next run's begin (or
// `total`; colour-order indices), vertex m of constraint runs[r].begin + k at solver index
// first[m] + k; each result into out[its index].
template <int K, int AXES, typename Kernel>
PLIANT_AVX2_INLINE void runs8(const SoaDisplaced& p, const LatticeRun* runs, std::int64_t r0,
                              std::int64_t r1, std::int64_t num_runs, std::int64_t total,
                              float* out, const Kernel& kernel) {
    for (std::int64_t r = r0; r < r1; ++r) {
        const LatticeRun& run = runs[r];
        const std::int64_t count = (r + 1 < num_runs ? runs[r + 1].begin : total) - run.begin;
        for (std::int64_t k = 0; k < count; k += 8) {
            Displaced8 v[K];
            for (int m = 0; m < K; ++m) {
                v[m] = load8<AXES>(p, run.first[static_cast<std::size_t>(m)] + k);
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
}

// runs8 with the kernel Kernel<AXES> for the run-time `axes` (0 .. 7).
template <int K, template <int> class Kernel>
PLIANT_AVX2_INLINE void runs8_axes(const SoaDisplaced& p, int axes, const LatticeRun* runs,
                                   std::int64_t r0, std::int64_t r1, std::int64_t num_runs,
                                   std::int64_t total, float* out) {
    switch (axes & 7) {
        case 0:
            runs8<K, 0>(p, runs, r0, r1, num_runs, total, out, Kernel<0>{});
            break;
        case 1:
            runs8<K, 1>(p, runs, r0, r1, num_runs, total, out, Kernel<1>{});
            break;
        case 2:
            runs8<K, 2>(p, runs, r0, r1, num_runs, total, out, Kernel<2>{});
            break;
        case 3:
            runs8<K, 3>(p, runs, r0, r1, num_runs, total, out, Kernel<3>{});
            break;
        case 4:
            runs8<K, 4>(p, runs, r0, r1, num_runs, total, out, Kernel<4>{});
            break;
        case 5:
            runs8<K, 5>(p, runs, r0, r1, num_runs, total, out, Kernel<5>{});
            break;
        case 6:
            runs8<K, 6>(p, runs, r0, r1, num_runs, total, out, Kernel<6>{});
            break;
        default:
            runs8<K, 7>(p, runs, r0, r1, num_runs, total, out, Kernel<7>{});
            break;
    }
}

}  // namespace

PLIANT_AVX2_FN void displaced_lengths_runs_avx2(const SoaDisplaced& p, int axes,
                                                const LatticeRun* runs, std::int64_t r0,
                                                std::int64_t r1, std::int64_t num_runs,
                                                std::int64_t total, float* rest_lengths) {
    runs8_axes<2, Length8>(p, axes, runs, r0, r1, num_runs, total, rest_lengths);
}

PLIANT_AVX2_FN void displaced_volumes_runs_avx2(const SoaDisplaced& p, int axes,
                                                const LatticeRun* runs, std::int64_t r0,
                                                std::int64_t r1, std::int64_t num_runs,
                                                std::int64_t total, float* rest_volumes) {
    runs8_axes<4, Volume8>(p, axes, runs, r0, r1, num_runs, total, rest_volumes);
}

#else  // no AVX2 on this target
void displaced_lengths_runs_avx2(const SoaDisplaced&, int, const LatticeRun*, std::int64_t,
                                 std::int64_t, std::int64_t, std::int64_t, float*) {}
void displaced_volumes_runs_avx2(const SoaDisplaced&, int, const LatticeRun*, std::int64_t,
                                 std::int64_t, std::int64_t, std::int64_t, float*) {}
#endif

}  // namespace pliant::pbd::detail
