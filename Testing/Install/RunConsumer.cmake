# ctest script, two steps sharing one install:
#   cmake -DSTEP=install  -DBUILD_DIR=<build tree> -DPREFIX=<dir> -P RunConsumer.cmake
#     installs the build tree into a fresh PREFIX and checks its layout (one targets file and one include
#     folder per component) and the installed `cementsph --version`;
#   cmake -DSTEP=consumer -DPREFIX=<dir> -DGROUP=<sph|imagingio|ctscene|drr|all|unknown> -DCONSUMER_SOURCE=<dir>
#         -DWORK_DIR=<dir> -P RunConsumer.cmake
#     configures, builds and runs the consumer project for GROUP against PREFIX only (CMAKE_PREFIX_PATH; the
#     source tree is never named). GROUP unknown must fail to configure, naming the unknown component; GROUP
#     each configures and links the consumer once per installed component, that component alone.
foreach(var STEP PREFIX)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "RunConsumer.cmake: ${var} is not set")
  endif()
endforeach()

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                  WORKING_DIRECTORY ${step_directory})
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

if(STEP STREQUAL "install")
  set(step_directory ${BUILD_DIR})
  file(REMOVE_RECURSE ${PREFIX})
  step("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})
  foreach(file lib/cmake/CementSPH/CementSPHConfig.cmake lib/cmake/CementSPH/CementSPHBuildFlagsTargets.cmake
               lib/cmake/CementSPH/CementSPHSPHTargets.cmake lib/cmake/CementSPH/CementSPHDRRTargets.cmake
               include/CementSPH/SPH/cementsph/sph/Kernels.h include/CementSPH/DRR/cementsph/drr/vtkDRRFilter.h
               include/CementSPH/CTScene/vtkSPHInjectionFilter.h lib/libCementSPH_SPH.a)
    if(NOT EXISTS ${PREFIX}/${file})
      file(GLOB_RECURSE found RELATIVE ${PREFIX} ${PREFIX}/*)
      message(FATAL_ERROR "install did not put ${file} in place; it installed: ${found}")
    endif()
  endforeach()
  # Per-component include folders: nothing merged into include/ itself.
  if(EXISTS ${PREFIX}/include/cementsph)
    message(FATAL_ERROR "install merged module headers into ${PREFIX}/include/cementsph; each belongs in include/CementSPH/<component>")
  endif()
  # The installed program finds its subcommand programs in libexec/cementsph (Launcher.cpp).
  step("installed cementsph --version" ${PREFIX}/bin/cementsph --version)
  if(NOT step_output MATCHES "cementsph [0-9]")
    message(FATAL_ERROR "installed cementsph --version printed: ${step_output}")
  endif()
  message(STATUS "install: ok")
  return()
endif()

foreach(var GROUP CONSUMER_SOURCE WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "RunConsumer.cmake: ${var} is not set")
  endif()
endforeach()
if(NOT EXISTS ${PREFIX}/lib/cmake/CementSPH/CementSPHConfig.cmake)
  message(FATAL_ERROR "no CementSPH package in ${PREFIX}: the test Install.Package installs it (run it first)")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR})
set(step_directory ${WORK_DIR})
set(configure ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${WORK_DIR} -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${PREFIX} -DCONSUMER_GROUP=${GROUP})

if(GROUP STREQUAL "unknown")
  execute_process(COMMAND ${configure} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(rc EQUAL 0 OR NOT err MATCHES "CementSPH has no component 'NoSuchModule'")
    message(FATAL_ERROR "find_package(CementSPH COMPONENTS SPH NoSuchModule) should fail naming NoSuchModule; "
      "configure returned ${rc}:\n${out}\n${err}")
  endif()
  message(STATUS "unknown component refused: ok")
  return()
endif()

if(GROUP STREQUAL "each")
  # Every component by itself in a C++-only project: its package finds (and the C the config enables) must
  # be enough to generate and link. The list is the installed config's own.
  file(READ ${PREFIX}/lib/cmake/CementSPH/CementSPHConfig.cmake config)
  string(REGEX MATCH "set\\(_CementSPH_ALL_COMPONENTS \"([^\"]*)\"\\)" line "${config}")
  set(components "${CMAKE_MATCH_1}")
  list(LENGTH components count)
  if(count LESS 10)
    message(FATAL_ERROR "read ${count} components from the installed CementSPHConfig.cmake: '${line}'")
  endif()
  foreach(component IN LISTS components)
    set(step_directory ${WORK_DIR})
    step("configure consumer (${component} alone)" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${WORK_DIR}/${component}
         -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${PREFIX} -DCONSUMER_GROUP=one -DCONSUMER_COMPONENT=${component})
    step("link consumer (${component} alone)" ${CMAKE_COMMAND} --build ${WORK_DIR}/${component})
  endforeach()
  message(STATUS "each of the ${count} components configured and linked alone: ok")
  return()
endif()

step("configure consumer (${GROUP})" ${configure})
if(GROUP STREQUAL "sph")
  # Independently of the consumer's own checks: its cache holds no trace of VTK, ITK, MPI or a C compiler.
  file(STRINGS ${WORK_DIR}/CMakeCache.txt foreign REGEX "^(VTK_DIR|ITK_DIR|MPI_C_[A-Z_]*|HDF5_[A-Z_]*|CMAKE_C_COMPILER):")
  if(foreign)
    message(FATAL_ERROR "find_package(CementSPH COMPONENTS SPH) looked for more than Eigen and OpenMP: ${foreign}")
  endif()
endif()
step("build consumer (${GROUP})" ${CMAKE_COMMAND} --build ${WORK_DIR})
step("run consumer (${GROUP})" ${WORK_DIR}/consumer)
message(STATUS "${step_output}")
