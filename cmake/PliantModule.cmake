# pliant_add_module(NAME <name> SOURCES <files...> DEPS <targets...>)
# One static library per module, target pliant_<name>, alias pliant::<name>. Headers live beside
# the sources under src/pliant/<name>/ and are included as "pliant/<name>/<file>.hpp".
# DEPS are PUBLIC: the module graph in DESIGN.md is exactly these link lines.
function(pliant_add_module)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;DEPS" ${ARGN})
  set(target pliant_${ARG_NAME})
  add_library(${target} STATIC ${ARG_SOURCES})
  add_library(pliant::${ARG_NAME} ALIAS ${target})
  target_include_directories(${target} PUBLIC ${PROJECT_SOURCE_DIR}/src)
  target_link_libraries(${target} PUBLIC ${ARG_DEPS})
  target_compile_features(${target} PUBLIC cxx_std_20)
  pliant_set_warnings(${target})
endfunction()
