# The third-party libraries the pliant library links, found from Debian packages (see
# ../shared/DEPENDENCIES.md). Included by the build (PliantDependencies.cmake) and, installed, by
# pliantConfig.cmake, so that a project using the installed package finds the same targets.
find_package(Threads REQUIRED)
find_package(TBB CONFIG REQUIRED)
find_package(fmt CONFIG REQUIRED)
find_package(nlohmann_json 3.11 CONFIG REQUIRED)
find_package(tinyobjloader CONFIG REQUIRED)
# stb has no CMake config; libstb.so holds the implementations (define no STB_*_IMPLEMENTATION).
find_package(PkgConfig REQUIRED)
if(NOT TARGET PkgConfig::STB)
  pkg_check_modules(STB REQUIRED IMPORTED_TARGET stb)
endif()

# NIfTI-1 (niftilib) and zlib. find_package(NIFTI CONFIG) is broken on Debian (its targets name
# files that do not exist): find the pieces by hand (../shared/DEPENDENCIES.md). Link libniftiio
# (NIfTI-1 API) only, never libnifti2 too: they export the same symbol names.
find_package(ZLIB REQUIRED)
find_path(NIFTI_INCLUDE_DIR nifti1_io.h PATH_SUFFIXES nifti REQUIRED)
find_library(NIFTI_NIFTIIO_LIBRARY niftiio REQUIRED)
find_library(NIFTI_ZNZ_LIBRARY znz REQUIRED)
if(NOT TARGET nifti::niftiio)
  add_library(nifti::niftiio INTERFACE IMPORTED)
  target_include_directories(nifti::niftiio INTERFACE ${NIFTI_INCLUDE_DIR})
  target_link_libraries(nifti::niftiio INTERFACE ${NIFTI_NIFTIIO_LIBRARY} ${NIFTI_ZNZ_LIBRARY} ZLIB::ZLIB m)
endif()
