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

# PLIANT_NATIVE (default OFF, a portable x86-64 library; `make demo`, `make test` and the release
# preset turn it ON): compile for the build machine's CPU (the compiler may then use AVX2 and
# AVX-512 anywhere), 1.25-1.3x faster cloth on the drape scene. Every build gives the same
# bits for 1 and N threads. A native build's results can differ in the last bits from a portable
# one's: GCC 12 fuses a vectorized pair a·b − c·d, e·f + g·h into one fmaddsub instruction even
# under -ffp-contract=off (it does where scenes rotate meshes, cloth/motion.hpp). Adding -mno-fma
# -mno-avx512f would rule that out and give the portable bits, for 1.17x instead of 1.3x
# (docs/journal/2026-11-25-native-build-solver-floor.md).
if(PLIANT_NATIVE)
  add_compile_options($<$<COMPILE_LANGUAGE:CXX>:-march=native>)
endif()

# PLIANT_GLUE_OPTIMIZATION (default empty: the build type's): the optimization flag of the sources
# that read, write, parse and call rather than compute: the io and pipeline modules
# (pliant_add_module's GLUE) and the command-line tool (apps/pliant). scripts/sanitize sets -O0:
# with ASan + UBSan they are the costliest sources to compile (nlohmann::json, CLI11, OpenVDB
# and GDCM headers: io, pipeline and apps/pliant were 42 % of the ASan tree's build;
# apps/pliant/cmd_cloth.cpp compiles in 23 s at -O0 against 41 at -O1), and the tests spend
# little of their time in them.
set(PLIANT_GLUE_OPTIMIZATION "" CACHE STRING
  "Optimization flag of the io and pipeline modules and the CLI (empty: the build type's)")
