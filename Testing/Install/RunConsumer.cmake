# ctest script: installs the build tree into a fresh prefix, then configures, builds and runs the
# consumer project against that prefix only (CMAKE_PREFIX_PATH; the source tree is never named).
#   cmake -DBUILD_DIR=... -DWORK_DIR=... -DCONSUMER_SOURCE=... -P RunConsumer.cmake
foreach(var BUILD_DIR WORK_DIR CONSUMER_SOURCE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "RunConsumer.cmake: ${var} is not set")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

function(step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${what} failed (${rc}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

step("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
foreach(file lib/cmake/CementSPH/CementSPHConfig.cmake lib/cmake/CementSPH/CementSPHTargets.cmake
             include/cementsph/sph/HagenPoiseuille.h lib/libCementSPH_SPH.a)
  if(NOT EXISTS ${prefix}/${file})
    file(GLOB_RECURSE found RELATIVE ${prefix} ${prefix}/*)
    message(FATAL_ERROR "install did not put ${file} in place; it installed: ${found}")
  endif()
endforeach()
# The installed program finds its subcommand programs in libexec/cementsph (Launcher.cpp).
step("installed cementsph --version" ${prefix}/bin/cementsph --version)
if(NOT step_output MATCHES "cementsph [0-9]")
  message(FATAL_ERROR "installed cementsph --version printed: ${step_output}")
endif()
step("configure consumer" ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE} -B ${WORK_DIR}/consumer-build
     -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix})
step("build consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/consumer-build)
step("run consumer" ${WORK_DIR}/consumer-build/consumer)
message(STATUS "${step_output}")
