# Code generation for every C++ target (a CUDA backend's nvcc flags would be its own).
#
# -ffp-contract=off: a * b + c is never contracted into an fma. GCC's default for C++ is
# -ffp-contract=fast, which contracts wherever the target has fma (any -march with it, e.g.
# native on this project's machines) and differently in different inlining contexts. pliant needs
# the same rounding everywhere: expansion arithmetic (geometry/exact_predicates.cpp) is exact only
# without contraction, and the scalar and SIMD kernels (cloth constraints, PBD projection,
# resampling, ray casting) are tested to give the same bits, also against the reference code the
# tests compute themselves. No code relies on contraction.
add_compile_options($<$<COMPILE_LANGUAGE:CXX>:-ffp-contract=off>)

# PLIANT_NATIVE (default ON): compile for the build machine's CPU (the compiler may then use AVX2
# and AVX-512 anywhere), about 1.25x faster cloth on the drape scene. Without contraction and without
# -ffast-math the compiler keeps every floating-point operation and its order, so the results are
# the portable build's, bit for bit (docs/performance.md). Turn it OFF for a binary that must run
# on any x86-64.
if(PLIANT_NATIVE)
  add_compile_options($<$<COMPILE_LANGUAGE:CXX>:-march=native>)
endif()
