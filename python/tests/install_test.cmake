# ctest python_installed: `cmake --install BUILD_DIR --prefix PREFIX` into a fresh prefix, then
# CHECK (installed_import.py) run by PYTHON with only PREFIX/SITE_DIR on PYTHONPATH: the package
# must come from the prefix and reproduce the cloth-funnel counts.
foreach(var BUILD_DIR PREFIX SITE_DIR PYTHON CHECK SHARED_DATA_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "install_test.cmake: -D ${var}=... is required")
  endif()
endforeach()
file(REMOVE_RECURSE ${PREFIX})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX}
                RESULT_VARIABLE result OUTPUT_QUIET)
if(result)
  message(FATAL_ERROR "cmake --install ${BUILD_DIR} --prefix ${PREFIX} failed: ${result}")
endif()
set(ENV{PYTHONPATH} ${PREFIX}/${SITE_DIR})
set(ENV{PYTHONDONTWRITEBYTECODE} 1)
execute_process(COMMAND ${PYTHON} ${CHECK} ${PREFIX} ${SHARED_DATA_DIR}
                WORKING_DIRECTORY ${PREFIX}
                RESULT_VARIABLE result)
if(result)
  message(FATAL_ERROR "${CHECK} failed on the installed package: ${result}")
endif()
file(REMOVE_RECURSE ${PREFIX})
