# Builds and runs tests/consumer/project against edgeplane.  -DMODE=subdirectory|find_package
# -DSOURCE_DIR=<edgeplane source> -DWORK_DIR=<scratch dir>
file(REMOVE_RECURSE ${WORK_DIR})
set(project_dir ${SOURCE_DIR}/tests/consumer/project)
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "command failed (${rc}): ${ARGN}")
  endif()
endfunction()
if(MODE STREQUAL "find_package")
  run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/lib -DEDGEPLANE_BUILD_TESTS=OFF -DEDGEPLANE_BUILD_EXAMPLES=OFF
      -DEDGEPLANE_BUILD_BENCHMARKS=OFF -DEDGEPLANE_ENABLE_CUDA=OFF -DCMAKE_INSTALL_PREFIX=${WORK_DIR}/prefix)
  run(${CMAKE_COMMAND} --install ${WORK_DIR}/lib)
  run(${CMAKE_COMMAND} -S ${project_dir} -B ${WORK_DIR}/consumer -DUSE_FIND_PACKAGE=ON
      -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release)
else()
  run(${CMAKE_COMMAND} -S ${project_dir} -B ${WORK_DIR}/consumer -DEDGEPLANE_SOURCE_DIR=${SOURCE_DIR}
      -DEDGEPLANE_ENABLE_CUDA=OFF -DCMAKE_BUILD_TYPE=Release)
endif()
run(${CMAKE_COMMAND} --build ${WORK_DIR}/consumer)
run(${WORK_DIR}/consumer/consumer)
