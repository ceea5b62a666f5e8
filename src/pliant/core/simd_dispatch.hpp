// Run-time choice of SIMD kernels. Kernels that use AVX2 are compiled for it with a function
// attribute (PLIANT_AVX2_FN) in files of their own, so that a portable build (PLIANT_NATIVE=OFF,
// baseline x86-64) has them too, and are called only when has_avx2() says the CPU runs them.
// Such kernels do the IEEE operations of their scalar twins lane by lane in the same order and
// never use FMA (-ffp-contract=off for every file, cmake/PliantCodegen.cmake; under -march=native
// GCC 12 can still fuse a vectorized a·b − c·d, e·f + g·h pair into fmaddsub, which these kernels
// do not contain): the choice never changes a bit of an output, and tests compare the two paths by
// switching AVX2 off with allow_avx2(false), in the build that runs them.
//
// PLIANT_HAS_AVX2_TARGET is defined where the compiler can build such kernels (x86-64, g++ or
// clang); elsewhere the AVX2 files compile to stubs and has_avx2() is false.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define PLIANT_HAS_AVX2_TARGET 1
#define PLIANT_AVX2_FN __attribute__((target("avx2")))
#define PLIANT_AVX2_INLINE inline __attribute__((target("avx2"), always_inline))
#endif

namespace pliant {

// Whether the CPU runs AVX2 and AVX2 kernels are allowed (allow_avx2). Thread safe.
bool has_avx2();
// false makes has_avx2() false until called with true: for tests and benchmarks that compare the
// kernels. Process-wide; not to be called while kernels that ask has_avx2() run.
void allow_avx2(bool allowed);

}  // namespace pliant
