# Install rules: `cmake --install BUILD --prefix P` puts
#   P/include/pliant/<module>/*.hpp          every module's headers (detail/ too: templates use them)
#   P/lib/libpliant_<module>.a               one static library per module
#   P/lib/cmake/pliant/pliantConfig.cmake    find_package(pliant): targets pliant::core … pliant::pipeline
#   P/lib/pkgconfig/pliant.pc                pkg-config --cflags --libs pliant
#   P/bin/pliant                             the CLI, when PLIANT_BUILD_APPS
# A consumer links the modules it uses (pliant::collision, pliant::cloth, …); each brings the
# modules and third-party libraries it needs. tests/consumer is such a project (scripts/check-install).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(PLIANT_MODULES core geometry bvh collision cloth volume pbd render nerf io pipeline)
set(_pliant_targets)
foreach(module IN LISTS PLIANT_MODULES)
  set_target_properties(pliant_${module} PROPERTIES EXPORT_NAME ${module})
  target_include_directories(pliant_${module} PUBLIC $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  list(APPEND _pliant_targets pliant_${module})
endforeach()

install(TARGETS ${_pliant_targets} EXPORT pliantTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/pliant/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pliant
        FILES_MATCHING PATTERN "*.hpp")
install(DIRECTORY ${PROJECT_BINARY_DIR}/generated/pliant/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/pliant
        FILES_MATCHING PATTERN "*.hpp")
if(TARGET pliant)
  install(TARGETS pliant RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

set(PLIANT_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/pliant)
install(EXPORT pliantTargets NAMESPACE pliant:: DESTINATION ${PLIANT_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/pliantConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/pliantConfig.cmake
                              INSTALL_DESTINATION ${PLIANT_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/pliantConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/pliantConfig.cmake ${PROJECT_BINARY_DIR}/pliantConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/PliantLibraryDependencies.cmake
        DESTINATION ${PLIANT_CMAKE_DIR})

# pkg-config: every module in link order (dependents first), then the third-party libraries.
set(PLIANT_PC_LIBS "")
foreach(module pipeline io nerf render pbd volume cloth collision bvh geometry core)
  string(APPEND PLIANT_PC_LIBS " -lpliant_${module}")
endforeach()
# Libraries without a pkg-config file of their own (found by hand in PliantLibraryDependencies).
set(PLIANT_PC_EXTRA_LIBS "-lnifti2 -lznz")
if(TARGET pliant_gdcm)
  string(APPEND PLIANT_PC_EXTRA_LIBS " -lgdcmMSFF -lgdcmDSED -lgdcmCommon")
endif()
if(TARGET pliant_openvdb)
  string(APPEND PLIANT_PC_EXTRA_LIBS " -lopenvdb -lImath")
endif()
# Relocatable: the prefix is found from the .pc file's own directory (LIBDIR/pkgconfig).
file(RELATIVE_PATH PLIANT_PC_PREFIX_FROM_PCFILEDIR /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" PLIANT_PC_PREFIX_FROM_PCFILEDIR "${PLIANT_PC_PREFIX_FROM_PCFILEDIR}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/pliant.pc.in ${PROJECT_BINARY_DIR}/pliant.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/pliant.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
