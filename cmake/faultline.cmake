# Small helpers that keep the per-directory CMakeLists short.
include(${CMAKE_CURRENT_LIST_DIR}/gtest_suites.cmake)

# Warnings for our own targets; generated protobuf code is compiled without them. PRODUCT (libraries, nodes, the
# tool) adds gcc's -Wconversion: an implicit narrowing (double to int, 64 to 32 bits, int to uint8) in the product is
# written as a cast that says it is meant. Tests are left without it (gtest's comparisons of literals would drown
# it), and so is clang, whose -Wconversion also holds every sign conversion.
function(faultline_warnings target)
  cmake_parse_arguments(ARG "PRODUCT" "" "" ${ARGN})
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow)
  if(ARG_PRODUCT)
    target_compile_options(${target} PRIVATE $<$<CXX_COMPILER_ID:GNU>:-Wconversion>)
  endif()
  if(FAULTLINE_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  if(FAULTLINE_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=${FAULTLINE_SANITIZE} -fno-omit-frame-pointer)
    target_link_options(${target} PRIVATE -fsanitize=${FAULTLINE_SANITIZE})
  endif()
endfunction()

# faultline_add_library(<concern> SOURCES ... LIBS ...): static library faultline_<concern>, include root lib/.
function(faultline_add_library concern)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_library(faultline_${concern} STATIC ${ARG_SOURCES})
  target_include_directories(faultline_${concern} PUBLIC ${PROJECT_SOURCE_DIR}/lib)
  target_compile_features(faultline_${concern} PUBLIC cxx_std_17)
  target_link_libraries(faultline_${concern} PUBLIC ${ARG_LIBS})
  faultline_warnings(faultline_${concern} PRODUCT)
endfunction()

# faultline_add_test(<name> SOURCES ... LIBS ... [LABELS ...] [RESOURCE_LOCK <lock>] [SCALAR_TOO]): one GoogleTest
# executable, one CTest test per GoogleTest suite (cmake/gtest_suites.cmake), built after the fixtures are unpacked
# (tests/test_data.hpp says where they are). SCALAR_TOO registers every suite a second time as scalar.<suite> with
# FAULTLINE_SCALAR=1, so the portable fallbacks of the hand-dispatched SIMD kernels are held to the same assertions
# (goldens included) on a CPU that has the vector units. RESOURCE_LOCK keeps suites that share something outside
# the process (e.g. a DDS domain) from running at the same time under ctest -j.
function(faultline_add_test name)
  cmake_parse_arguments(ARG "SCALAR_TOO" "RESOURCE_LOCK" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gmock GTest::gtest_main)
  target_compile_definitions(${name} PRIVATE
    FAULTLINE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    FAULTLINE_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data"
    FAULTLINE_UNPACKED_TEST_DATA_DIR="${FAULTLINE_UNPACKED_TEST_DATA_DIR}"
    FAULTLINE_BIN_DIR="${CMAKE_RUNTIME_OUTPUT_DIRECTORY}")
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  add_dependencies(${name} faultline_test_data)
  faultline_warnings(${name})
  faultline_discover_suites(${name} LABELS ${ARG_LABELS} RESOURCE_LOCK "${ARG_RESOURCE_LOCK}")
  if(ARG_SCALAR_TOO)
    faultline_discover_suites(${name} PREFIX "scalar." LABELS ${ARG_LABELS} scalar ENVIRONMENT "FAULTLINE_SCALAR=1"
      RESOURCE_LOCK "${ARG_RESOURCE_LOCK}")
  endif()
endfunction()

# faultline_add_node(<name> LIBS ...): nodes/<name>/main.cpp -> bin/<name>.
function(faultline_add_node name)
  cmake_parse_arguments(ARG "" "" "LIBS" ${ARGN})
  add_executable(${name} ${CMAKE_CURRENT_SOURCE_DIR}/${name}/main.cpp)
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  faultline_warnings(${name} PRODUCT)
endfunction()
