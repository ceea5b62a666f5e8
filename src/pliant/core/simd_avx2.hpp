// Element-wise AVX2 helpers shared by the runtime-dispatched kernels (cloth constraints, soft
// body projections, resampling): short names over the intrinsics, so a kernel reads like its
// scalar twin. Use only inside functions compiled for AVX2 (PLIANT_AVX2_FN / PLIANT_AVX2_INLINE,
// core/simd_dispatch.hpp) and reached after has_avx2(). No FMA anywhere: a lane computes the
// scalar code's bits.
#pragma once

#include <immintrin.h>

#include "pliant/core/simd_dispatch.hpp"

namespace pliant::simd {

PLIANT_AVX2_INLINE __m256d add(__m256d a, __m256d b) {
    return _mm256_add_pd(a, b);
}
PLIANT_AVX2_INLINE __m256d sub(__m256d a, __m256d b) {
    return _mm256_sub_pd(a, b);
}
PLIANT_AVX2_INLINE __m256d mul(__m256d a, __m256d b) {
    return _mm256_mul_pd(a, b);
}
PLIANT_AVX2_INLINE __m256d div(__m256d a, __m256d b) {
    return _mm256_div_pd(a, b);
}
PLIANT_AVX2_INLINE __m256d set1(double x) {
    return _mm256_set1_pd(x);
}
// mask ? a : b per lane (mask: a compare result, all ones or all zeros per lane).
PLIANT_AVX2_INLINE __m256d select(__m256d mask, __m256d a, __m256d b) {
    return _mm256_blendv_pd(b, a, mask);
}

PLIANT_AVX2_INLINE __m256 add(__m256 a, __m256 b) {
    return _mm256_add_ps(a, b);
}
PLIANT_AVX2_INLINE __m256 sub(__m256 a, __m256 b) {
    return _mm256_sub_ps(a, b);
}
PLIANT_AVX2_INLINE __m256 mul(__m256 a, __m256 b) {
    return _mm256_mul_ps(a, b);
}

}  // namespace pliant::simd
