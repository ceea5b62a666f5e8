# pliant_set_warnings(target): the project's warning set, errors in CI-like builds.
option(PLIANT_WERROR "Treat warnings as errors" ON)
function(pliant_set_warnings target)
  target_compile_options(${target} PRIVATE
    -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wcast-align -Woverloaded-virtual
    -Wnull-dereference -Wimplicit-fallthrough -Wmissing-declarations
    $<$<BOOL:${PLIANT_WERROR}>:-Werror>)
endfunction()
