# Warnings on for our own targets (not for third-party headers, which come in as SYSTEM).
add_library(cementsph_warnings INTERFACE)
target_compile_options(cementsph_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>)
add_library(CementSPH::warnings ALIAS cementsph_warnings)

add_library(cementsph_optimise INTERFACE)
if(CEMENTSPH_NATIVE)
  target_compile_options(cementsph_optimise INTERFACE -march=native)
endif()
add_library(CementSPH::optimise ALIAS cementsph_optimise)
