#include "pliant/core/simd_dispatch.hpp"

#include <atomic>

namespace pliant {

namespace {
std::atomic<bool> g_avx2_allowed{true};
}  // namespace

void allow_avx2(bool allowed) {
    g_avx2_allowed.store(allowed, std::memory_order_relaxed);
}

bool has_avx2() {
#if defined(PLIANT_HAS_AVX2_TARGET)
    static const bool CPU_HAS_AVX2 = __builtin_cpu_supports("avx2") != 0;
    return CPU_HAS_AVX2 && g_avx2_allowed.load(std::memory_order_relaxed);
#else
    return false;
#endif
}

}  // namespace pliant
