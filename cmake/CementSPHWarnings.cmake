# Warnings on for our own targets (not for third-party headers, which come in as SYSTEM).
add_library(cementsph_warnings INTERFACE)
target_compile_options(cementsph_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion>)
# CI builds with warnings as errors (issue 24 item 4: .ci/run sets CEMENTSPH_WERROR=ON through scripts/build.sh),
# so a new warning stops a change from landing; a user's build with a newer compiler is not stopped by one.
option(CEMENTSPH_WERROR "Treat warnings in CementSPH's own code as errors" OFF)
if(CEMENTSPH_WERROR)
  target_compile_options(cementsph_warnings INTERFACE $<$<CXX_COMPILER_ID:GNU,Clang>:-Werror>)
endif()
add_library(CementSPH::warnings ALIAS cementsph_warnings)

add_library(cementsph_optimise INTERFACE)
if(CEMENTSPH_NATIVE)
  target_compile_options(cementsph_optimise INTERFACE -march=native)
endif()
add_library(CementSPH::optimise ALIAS cementsph_optimise)
