# Configure, build and run the consumer project against pik.
#   -DSRC=<this dir> -DWORK=<scratch dir>
#   and either -DPIK_DIR=<pik build tree> or -DINSTALL_FROM=<pik build tree to install>
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")
if(INSTALL_FROM)
  execute_process(COMMAND ${CMAKE_COMMAND} --install "${INSTALL_FROM}" --prefix "${WORK}/prefix"
                  RESULT_VARIABLE rc OUTPUT_QUIET)
  if(rc)
    message(FATAL_ERROR "cmake --install failed (${rc})")
  endif()
  set(PIK_DIR "${WORK}/prefix/lib/cmake/pik")
  if(NOT EXISTS "${PIK_DIR}/pikConfig.cmake")
    file(GLOB_RECURSE cfg "${WORK}/prefix/*/pikConfig.cmake")
    get_filename_component(PIK_DIR "${cfg}" DIRECTORY)
  endif()
  if(NOT EXISTS "${WORK}/prefix/bin/pikg-gen")
    message(FATAL_ERROR "install prefix has no bin/pikg-gen")
  endif()
  execute_process(COMMAND "${WORK}/prefix/bin/pikg-gen" --version RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "installed pikg-gen --version failed (${rc})")
  endif()
endif()
foreach(step
    "${CMAKE_COMMAND};-S;${SRC};-B;${WORK}/build;-Dpik_DIR=${PIK_DIR};-DCMAKE_BUILD_TYPE=Release"
    "${CMAKE_COMMAND};--build;${WORK}/build;-j2"
    "${WORK}/build/consumer")
  execute_process(COMMAND ${step} RESULT_VARIABLE rc)
  if(rc)
    string(REPLACE ";" " " shown "${step}")
    message(FATAL_ERROR "consumer step failed (${rc}): ${shown}")
  endif()
endforeach()
