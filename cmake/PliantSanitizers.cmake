# PLIANT_SANITIZE: a semicolon list of sanitizers applied to every target (address;undefined, thread).
set(PLIANT_SANITIZE "" CACHE STRING "Sanitizers for all targets, e.g. address;undefined or thread")
if(PLIANT_SANITIZE)
  list(JOIN PLIANT_SANITIZE "," _pliant_san)
  add_compile_options(-fsanitize=${_pliant_san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${_pliant_san})
endif()
