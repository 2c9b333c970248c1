# Fails when a test source uses a fixed temporary path: tests run in parallel (CTest runs every GoogleTest test in
# its own process, and two checkouts may test on one machine at once), so a fixed name under the temporary folder
# is shared and overwritten. Tests write only below a folder of their own:
#   C++     jointsim::test::TempDir (tests/test_util.hpp), jointsim::test::runCli / runCommand for CLI output;
#   Python  pytest's tmp_path / tmp_path_factory (or tempfile.mkdtemp);
#   shell   mktemp -d "${TMPDIR:-/tmp}/name.XXXXXX"; CMake scripts: mktemp -d.
# A line that needs such a text for another reason (a hostile path that must be rejected, a message) ends with the
# comment  tmp-path-ok: <why>  and is not reported.
#
# Usage: cmake -DSCAN_DIR=<folder> [-DEXCLUDE=<sub;folders>] [-DBASE_DIR=<folder>] [-DSTAMP=<file>] -P this
#   Scans SCAN_DIR/**/*.{cpp,hpp,h,py,sh,cmake} and CMakeLists.txt except below SCAN_DIR/<EXCLUDE...>; names every
#   finding as <file relative to BASE_DIR>:<line>: ...; FATAL_ERROR when there is one, else touches STAMP.
# Self-test: cmake -DSCAN_DIR=... -DEXPECT_VIOLATIONS=<file:line,file:line,...> [-DBASE_DIR=...] -P this
#   runs the check on SCAN_DIR in a child cmake and succeeds only when that fails and reports exactly those
#   findings (tests/CMakeLists.txt runs it on tests/data/temp_path_violation).
cmake_minimum_required(VERSION 3.20)

if(NOT DEFINED SCAN_DIR OR NOT IS_DIRECTORY "${SCAN_DIR}")
  message(FATAL_ERROR "check_test_temp_paths: SCAN_DIR='${SCAN_DIR}' is not a folder")
endif()
get_filename_component(SCAN_DIR "${SCAN_DIR}" ABSOLUTE)
if(NOT DEFINED BASE_DIR)
  set(BASE_DIR "${SCAN_DIR}")
endif()
get_filename_component(BASE_DIR "${BASE_DIR}" ABSOLUTE)

# ------------------------------------------------------------------------------------------------- self-test
if(DEFINED EXPECT_VIOLATIONS)
  execute_process(COMMAND "${CMAKE_COMMAND}" "-DSCAN_DIR=${SCAN_DIR}" "-DBASE_DIR=${BASE_DIR}"
                          -P "${CMAKE_CURRENT_LIST_FILE}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("${out}${err}")
  if(rc EQUAL 0)
    message(FATAL_ERROR "self-test: the check passed on ${SCAN_DIR}, expected it to fail")
  endif()
  string(REGEX MATCHALL "[^\n]*:[0-9]+: fixed temporary path" found "${err}")
  list(TRANSFORM found REPLACE ": fixed temporary path$" "")
  list(SORT found)
  string(REPLACE "," ";" expected "${EXPECT_VIOLATIONS}")
  list(SORT expected)
  if(NOT found STREQUAL expected)
    message(FATAL_ERROR "self-test: the check reported\n  ${found}\nexpected\n  ${expected}")
  endif()
  list(LENGTH found n)
  message(STATUS "self-test: the check failed as expected, naming the ${n} findings ${found}")
  return()
endif()

# ------------------------------------------------------------------------------------------------- the check
# The rules: a regular expression for one line, and (at the same index) what it found.
set(rule_regexes "temp_directory_path" "gettempdir" "P_tmpdir" "tmpnam" "[\"']/tmp/")
set(rule_names "std::filesystem::temp_directory_path()" "tempfile.gettempdir()" "P_tmpdir" "tmpnam()"
               "a literal path under /tmp")
set(shell_regex "(^|[ \t=(,])/tmp/")  # unquoted, in shell and CMake files only

set(hint "Tests run in parallel (and two checkouts may test at once): write only below a folder of the test's \
own, jointsim::test::TempDir (tests/test_util.hpp) in C++, pytest's tmp_path / tmp_path_factory in Python, \
mktemp -d in shell and CMake scripts. If such a path is never written (hostile input that must be rejected, a \
message), end its line with the comment  tmp-path-ok: <why>")

file(GLOB_RECURSE files LIST_DIRECTORIES false "${SCAN_DIR}/*")
list(SORT files)
set(excluded "")
foreach(e IN LISTS EXCLUDE)
  list(APPEND excluded "${SCAN_DIR}/${e}/")
endforeach()

set(findings 0)
foreach(f IN LISTS files)
  get_filename_component(name "${f}" NAME)
  if(NOT name MATCHES "\\.(cpp|hpp|h|py|sh|cmake)$" AND NOT name STREQUAL "CMakeLists.txt")
    continue()
  endif()
  set(skip FALSE)
  foreach(prefix IN LISTS excluded)
    string(FIND "${f}" "${prefix}" at)
    if(at EQUAL 0)
      set(skip TRUE)
    endif()
  endforeach()
  if(skip)
    continue()
  endif()
  set(shell_like FALSE)
  set(instead "jointsim::test::TempDir (tests/test_util.hpp)")
  if(name MATCHES "\\.(sh|cmake)$" OR name STREQUAL "CMakeLists.txt")
    set(shell_like TRUE)
    set(instead "mktemp -d \"\${TMPDIR:-/tmp}/NAME.XXXXXX\"")
  elseif(name MATCHES "\\.py$")
    set(instead "pytest's tmp_path or tmp_path_factory")
  endif()

  file(READ "${f}" text)
  # Fast path: most files have none of the texts.
  if(NOT text MATCHES "temp_directory_path|gettempdir|P_tmpdir|tmpnam|/tmp/")
    continue()
  endif()
  # One list element per line: characters that CMake lists treat specially are replaced first.
  string(REPLACE "\\" "<BSL>" text "${text}")
  string(REPLACE ";" "<SEMI>" text "${text}")
  string(REPLACE "[" "<LSB>" text "${text}")
  string(REPLACE "]" "<RSB>" text "${text}")
  string(REPLACE "\n" ";" lines "${text}")
  file(RELATIVE_PATH rel "${BASE_DIR}" "${f}")
  set(n 0)
  foreach(line IN LISTS lines)
    math(EXPR n "${n} + 1")
    if(line MATCHES "tmp-path-ok:")
      continue()
    endif()
    set(what "")
    set(i 0)
    foreach(regex IN LISTS rule_regexes)
      if(line MATCHES "${regex}")
        list(GET rule_names ${i} what)
        break()
      endif()
      math(EXPR i "${i} + 1")
    endforeach()
    if(what STREQUAL "" AND shell_like AND line MATCHES "${shell_regex}")
      set(what "a path under /tmp")
    endif()
    if(NOT what STREQUAL "")
      math(EXPR findings "${findings} + 1")
      message("${rel}:${n}: fixed temporary path (${what}); use ${instead} instead")
    endif()
  endforeach()
endforeach()

if(findings GREATER 0)
  message(FATAL_ERROR "check_test_temp_paths: ${findings} fixed temporary path(s) in ${SCAN_DIR} (listed above).\n"
                      "${hint}")
endif()
if(DEFINED STAMP)
  file(TOUCH "${STAMP}")
endif()
