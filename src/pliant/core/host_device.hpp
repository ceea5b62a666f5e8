// PLIANT_HOST_DEVICE marks per-element kernel functions that a CUDA backend compiles for both host
// and device. Such functions take trivially copyable data, never allocate, throw or call virtual
// functions. On CPU builds the macro is empty.
#pragma once

#if defined(__CUDACC__)
#define PLIANT_HOST_DEVICE __host__ __device__
#else
#define PLIANT_HOST_DEVICE
#endif

#if defined(__GNUC__)
#define PLIANT_FORCE_INLINE inline __attribute__((always_inline))
#define PLIANT_LIKELY(x) __builtin_expect(!!(x), 1)
#define PLIANT_UNLIKELY(x) __builtin_expect(!!(x), 0)
#else
#define PLIANT_FORCE_INLINE inline
#define PLIANT_LIKELY(x) (x)
#define PLIANT_UNLIKELY(x) (x)
#endif
