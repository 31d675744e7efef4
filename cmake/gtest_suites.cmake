# One CTest test per GoogleTest suite (not per test): each test process pays ~0.15-0.3 s of dynamic loading and
# static set-up, which over 5,000 single tests was a third of the suite's CPU time. A failing suite's output names
# the failing test (`[  FAILED  ] Suite.Test`); run one test with `<binary> --gtest_filter=Suite.Test`.
#
# faultline_discover_suites(<target> [PREFIX p] [LABELS ...] [ENVIRONMENT ...] [RESOURCE_LOCK lock]): after each
# build of <target>, lists its tests and writes the add_test() lines CTest includes (like gtest_discover_tests).

set(FAULTLINE_GTEST_SUITES_SCRIPT ${CMAKE_CURRENT_LIST_DIR}/gtest_suites_write.cmake)

function(faultline_discover_suites target)
  cmake_parse_arguments(ARG "" "PREFIX;RESOURCE_LOCK" "LABELS;ENVIRONMENT" ${ARGN})
  set(stem "${CMAKE_CURRENT_BINARY_DIR}/${target}${ARG_PREFIX}_suites")
  # Lists travel to the script '|'-separated: a ';' would split the custom command's argument.
  string(REPLACE ";" "|" labels "${ARG_LABELS}")
  string(REPLACE ";" "|" environment "${ARG_ENVIRONMENT}")
  set(ctest_file "${stem}_tests.cmake")
  set(include_file "${stem}_include.cmake")
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND ${CMAKE_COMMAND}
      -D "TEST_EXECUTABLE=$<TARGET_FILE:${target}>"
      -D "CTEST_FILE=${ctest_file}"
      -D "PREFIX=${ARG_PREFIX}"
      -D "LABELS=${labels}"
      -D "ENVIRONMENT=${environment}"
      -D "RESOURCE_LOCK=${ARG_RESOURCE_LOCK}"
      -D "WORKING_DIRECTORY=${CMAKE_CURRENT_BINARY_DIR}"
      -P ${FAULTLINE_GTEST_SUITES_SCRIPT}
    BYPRODUCTS ${ctest_file}
    VERBATIM)
  file(WRITE ${include_file}
    "if(EXISTS \"${ctest_file}\")\n  include(\"${ctest_file}\")\nelse()\n"
    "  add_test(${target}${ARG_PREFIX}_NOT_BUILT ${target}${ARG_PREFIX}_NOT_BUILT)\nendif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES ${include_file})
endfunction()
