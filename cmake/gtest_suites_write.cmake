# Script mode (cmake -P), run after a test binary is built: lists its GoogleTest suites and writes one add_test()
# per suite to CTEST_FILE. Inputs: TEST_EXECUTABLE CTEST_FILE PREFIX LABELS ENVIRONMENT RESOURCE_LOCK
# WORKING_DIRECTORY (see gtest_suites.cmake).
execute_process(COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
  WORKING_DIRECTORY "${WORKING_DIRECTORY}"
  OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE rc TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests failed (${rc}):\n${listing}\n${errors}")
endif()

# Suite lines start in column 0 and end with '.', optionally followed by "  # TypeParam = ...".
string(REPLACE ";" "\\;" listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(suites "")
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ #][^ ]*)\\.( .*)?$")
    list(APPEND suites "${CMAKE_MATCH_1}")
  endif()
endforeach()
list(REMOVE_DUPLICATES suites)

string(REPLACE "|" ";" LABELS "${LABELS}")
string(REPLACE "|" ";" ENVIRONMENT "${ENVIRONMENT}")
set(props "LABELS [==[${LABELS}]==] WORKING_DIRECTORY [==[${WORKING_DIRECTORY}]==]")
if(ENVIRONMENT)
  string(APPEND props " ENVIRONMENT [==[${ENVIRONMENT}]==]")
endif()
if(RESOURCE_LOCK)
  string(APPEND props " RESOURCE_LOCK [==[${RESOURCE_LOCK}]==]")
endif()
set(content "# Written by gtest_suites_write.cmake from ${TEST_EXECUTABLE} --gtest_list_tests\n")
foreach(suite IN LISTS suites)
  set(name "${PREFIX}${suite}")
  string(APPEND content
    "add_test([==[${name}]==] [==[${TEST_EXECUTABLE}]==] [==[--gtest_filter=${suite}.*]==])\n"
    "set_tests_properties([==[${name}]==] PROPERTIES ${props})\n")
endforeach()
file(WRITE "${CTEST_FILE}" "${content}")
