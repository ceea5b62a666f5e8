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

# niftilib's NIfTI-2 API (libnifti2, nifti2_io.h) reads NIfTI-1 and NIfTI-2 files. It exports the
# same symbol names as libniftiio (the NIfTI-1 API) with other structs, so io links libnifti2
# only, never nifti::niftiio too (../shared/DEPENDENCIES.md). Found by hand: Debian's NIFTI CMake
# config names files that do not exist.
find_library(PLIANT_NIFTI2_LIBRARY nifti2 REQUIRED)
if(NOT TARGET pliant_nifti2)
  add_library(pliant_nifti2 INTERFACE IMPORTED GLOBAL)
  target_include_directories(pliant_nifti2 INTERFACE ${NIFTI_INCLUDE_DIR})
  target_link_libraries(pliant_nifti2 INTERFACE ${PLIANT_NIFTI2_LIBRARY} ${NIFTI_ZNZ_LIBRARY} ZLIB::ZLIB m)
endif()

# GDCM 3 (Debian libgdcm-dev) for DICOM series. Found by hand rather than with find_package(GDCM):
# its config imports the gdcm-tools executables and VTK parts and warns about each one that is
# not installed. Without GDCM, pliant builds and DICOM reads are Unsupported.
find_path(PLIANT_GDCM_INCLUDE_DIR gdcmImageReader.h PATH_SUFFIXES gdcm-3.0)
set(PLIANT_IO_GDCM "")
foreach(lib gdcmMSFF gdcmDSED gdcmCommon)
  find_library(PLIANT_${lib}_LIBRARY ${lib})
endforeach()
if(PLIANT_GDCM_INCLUDE_DIR AND PLIANT_gdcmMSFF_LIBRARY AND PLIANT_gdcmDSED_LIBRARY
   AND PLIANT_gdcmCommon_LIBRARY)
  if(NOT TARGET pliant_gdcm)
    add_library(pliant_gdcm INTERFACE IMPORTED GLOBAL)
    target_include_directories(pliant_gdcm INTERFACE ${PLIANT_GDCM_INCLUDE_DIR})
    target_link_libraries(pliant_gdcm INTERFACE ${PLIANT_gdcmMSFF_LIBRARY}
      ${PLIANT_gdcmDSED_LIBRARY} ${PLIANT_gdcmCommon_LIBRARY})
    target_compile_definitions(pliant_gdcm INTERFACE PLIANT_HAS_GDCM=1)
  endif()
  set(PLIANT_IO_GDCM pliant_gdcm)
  message(STATUS "DICOM: GDCM found (${PLIANT_GDCM_INCLUDE_DIR})")
else()
  set(PLIANT_IO_GDCM "")
  message(STATUS "DICOM: GDCM not found (libgdcm-dev): DICOM reading disabled")
endif()

# OpenVDB 10 (Debian libopenvdb-dev + libboost-iostreams-dev) for .vdb volumes. Found by hand as
# GDCM is: Debian ships a find module with its own FindTBB beside it, not a config, and a
# consumer of the installed package should not need its module path. The headers include
# <Imath/half.h>, <tbb/…> and Boost headers from /usr/include; libopenvdb.so brings its own
# shared dependencies. Without OpenVDB, pliant builds and .vdb files are Unsupported.
find_path(PLIANT_OPENVDB_INCLUDE_DIR openvdb/openvdb.h)
find_library(PLIANT_OPENVDB_LIBRARY openvdb)
find_library(PLIANT_IMATH_LIBRARY NAMES Imath Imath-3_1)
find_path(PLIANT_BOOST_IOSTREAMS_INCLUDE_DIR boost/iostreams/device/array.hpp)
if(PLIANT_OPENVDB_INCLUDE_DIR AND PLIANT_OPENVDB_LIBRARY AND PLIANT_IMATH_LIBRARY
   AND PLIANT_BOOST_IOSTREAMS_INCLUDE_DIR)
  if(NOT TARGET pliant_openvdb)
    add_library(pliant_openvdb INTERFACE IMPORTED GLOBAL)
    target_include_directories(pliant_openvdb INTERFACE ${PLIANT_OPENVDB_INCLUDE_DIR})
    target_link_libraries(pliant_openvdb INTERFACE ${PLIANT_OPENVDB_LIBRARY}
      ${PLIANT_IMATH_LIBRARY} TBB::tbb)
    target_compile_definitions(pliant_openvdb INTERFACE PLIANT_HAS_OPENVDB=1)
  endif()
  set(PLIANT_IO_OPENVDB pliant_openvdb)
  message(STATUS "OpenVDB: found (${PLIANT_OPENVDB_LIBRARY})")
else()
  set(PLIANT_IO_OPENVDB "")
  message(STATUS "OpenVDB: not found (libopenvdb-dev libboost-iostreams-dev): .vdb disabled")
endif()
