# Every third-party dependency, found from Debian packages (see ../shared/DEPENDENCIES.md): the
# library's (PliantLibraryDependencies.cmake), then what the tools, tests and benchmarks need.
include(PliantLibraryDependencies)
if(PLIANT_BUILD_APPS)
  find_package(CLI11 CONFIG REQUIRED)
endif()

if(PLIANT_BUILD_TESTS)
  find_package(GTest CONFIG REQUIRED)
endif()
if(PLIANT_BUILD_BENCH)
  find_package(benchmark CONFIG REQUIRED)
endif()

set(PLIANT_HAS_EMBREE OFF)
if(PLIANT_WITH_EMBREE)
  find_package(embree 3 CONFIG QUIET)
  if(embree_FOUND)
    set(PLIANT_HAS_EMBREE ON)
  else()
    message(WARNING "Embree 3 not found: BVH benchmarks run without the Embree peer "
                    "(install libembree-dev, or scripts/install-deps)")
  endif()
endif()
