# pliant_add_module(NAME <name> SOURCES <files...> DEPS <targets...> [PRIVATE_DEPS <targets...>]
#                   [GLUE])
# One static library per module, target pliant_<name>, alias pliant::<name>. Headers live beside
# the sources under src/pliant/<name>/ and are included as "pliant/<name>/<file>.hpp".
# DEPS are PUBLIC: the pliant modules this one builds on and the third-party libraries its public
# headers include; the module graph in docs/architecture.md is exactly the pliant:: entries.
# PRIVATE_DEPS are used by the sources only, so they do not reach a caller's compile line (a static
# library still passes them on to the final link). GLUE: the module reads, writes, parses and
# calls rather than computes; it compiles with PLIANT_GLUE_OPTIMIZATION (cmake/PliantCodegen.cmake)
# and, with PLIANT_FUZZ, with libFuzzer's coverage instrumentation: the file readers the harnesses
# in fuzz/ call are in these modules (io, pipeline). The computing modules go without it, so the
# sanitized tests that share the fuzzing tree (scripts/sanitizer-tree) run at ASan's speed rather
# than with a coverage callback on every comparison.
function(pliant_add_module)
  cmake_parse_arguments(ARG "GLUE" "NAME" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  set(target pliant_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SOURCES})
  add_library(pliant::${ARG_NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_features(${target} PUBLIC cxx_std_20)
  pliant_set_warnings(${target})
  if(ARG_GLUE)
    target_compile_options(${target} PRIVATE ${PLIANT_GLUE_OPTIMIZATION})
    if(PLIANT_FUZZ)
      target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
    endif()
  endif()
endfunction()
