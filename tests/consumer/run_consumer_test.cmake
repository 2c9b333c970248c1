# Installs jointsim into a scratch prefix and builds + runs tests/consumer against it with
# find_package(jointsim). Invoked by CTest (see tests/CMakeLists.txt).
# The scratch folder is the test's own: made by mktemp -d under $TMPDIR (default /tmp), so that neither another
# test nor a second checkout testing at the same time can share it. Removed when the test passes, kept (and
# named) when it fails.
if(DEFINED ENV{TMPDIR} AND NOT "$ENV{TMPDIR}" STREQUAL "")
  set(_tmp_root "$ENV{TMPDIR}")
else()
  set(_tmp_root "/tmp")
endif()
execute_process(COMMAND mktemp -d "${_tmp_root}/jointsim_consumer.XXXXXX"
                OUTPUT_VARIABLE WORK_DIR OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR WORK_DIR STREQUAL "")
  message(FATAL_ERROR "mktemp -d under ${_tmp_root} failed (${rc})")
endif()

macro(fail text)
  message(FATAL_ERROR "${text} (scratch folder kept: ${WORK_DIR})")
endmacro()

execute_process(COMMAND ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${WORK_DIR}/prefix
                RESULT_VARIABLE rc OUTPUT_QUIET)
if(NOT rc EQUAL 0)
  fail("cmake --install failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/consumer -B ${WORK_DIR}/build -G ${GENERATOR}
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  fail("configuring the consumer project failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/build RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  fail("building the consumer project failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/build/consumer ${WORK_DIR}/prefix/share/jointsim/config/robots/ur5.urdf
                RESULT_VARIABLE rc OUTPUT_VARIABLE out)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  fail("the consumer program failed (${rc})")
endif()

# The README's C++ snippet as a reader pastes it: its CMakeLists.txt and main.cpp blocks, built against the same
# installed prefix and run on the installed config/ folder.
find_program(PYTHON3 python3 REQUIRED)
file(MAKE_DIRECTORY ${WORK_DIR}/readme_app)
foreach(part "cmake;CMakeLists.txt" "cpp;main.cpp")
  list(GET part 0 lang)
  list(GET part 1 name)
  execute_process(COMMAND ${PYTHON3} ${SOURCE_DIR}/tests/readme/snippets.py extract ${SOURCE_DIR}/README.md ${lang} 0
                  OUTPUT_FILE ${WORK_DIR}/readme_app/${name} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    fail("README.md has no ${lang} snippet to build (${rc})")
  endif()
endforeach()
execute_process(COMMAND ${CMAKE_COMMAND} -S ${WORK_DIR}/readme_app -B ${WORK_DIR}/readme_build -G ${GENERATOR}
                        -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix -DCMAKE_BUILD_TYPE=Release
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  fail("configuring the README's C++ snippet failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${WORK_DIR}/readme_build RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  fail("building the README's C++ snippet failed (${rc})")
endif()
execute_process(COMMAND ${WORK_DIR}/readme_build/app ${WORK_DIR}/prefix/share/jointsim/config
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "README snippet: ${out}${err}")
if(NOT rc EQUAL 0 OR NOT out MATCHES "q_elbow_joint")
  fail("the README's C++ snippet failed (${rc})")
endif()
file(REMOVE_RECURSE ${WORK_DIR})
