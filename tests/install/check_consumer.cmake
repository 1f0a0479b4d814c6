# Run by ctest in script mode: builds a consumer project against Tessera and runs it.
# MODE=find_package installs the already-built tree into WORK_DIR/prefix first.
file(REMOVE_RECURSE ${WORK_DIR})
set(consumer_args -G Ninja -S ${CONSUMER_DIR} -B ${WORK_DIR}/build -DCMAKE_BUILD_TYPE=Release)
if(MODE STREQUAL "find_package")
  execute_process(COMMAND ${CMAKE_COMMAND} --install ${TESSERA_BINARY_DIR}
                          --prefix ${WORK_DIR}/prefix
                  RESULT_VARIABLE result OUTPUT_QUIET)
  if(result)
    message(FATAL_ERROR "cmake --install failed: ${result}")
  endif()
  list(APPEND consumer_args -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
else()
  # The source tree compiles its kernels once (native), unoptimised (Debug), and only what
  # the consumer links: how a source tree is consumed depends neither on the SIMD targets
  # nor on the optimisation, and the full optimised build with every target is the
  # enclosing one (this test took 325 s uncached on two cores with every target, 158 s in
  # CI with native at -O3 beside the other tests).
  list(REMOVE_ITEM consumer_args -DCMAKE_BUILD_TYPE=Release)
  list(APPEND consumer_args -DCMAKE_BUILD_TYPE=Debug -DTESSERA_SOURCE_DIR=${TESSERA_SOURCE_DIR}
                            -DTESSERA_DOUBLE=${TESSERA_DOUBLE} -DTESSERA_SIMD=native)
endif()
foreach(step configure build run)
  if(step STREQUAL "configure")
    set(command ${CMAKE_COMMAND} ${consumer_args})
  elseif(step STREQUAL "build")
    set(command ${CMAKE_COMMAND} --build ${WORK_DIR}/build --parallel 2 --target consumer)
  else()
    set(command ${WORK_DIR}/build/consumer)
  endif()
  execute_process(COMMAND ${command} RESULT_VARIABLE result OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(result)
    message(FATAL_ERROR "consumer ${step} failed (${result}):\n${out}\n${err}")
  endif()
endforeach()
message(STATUS "${out}")
