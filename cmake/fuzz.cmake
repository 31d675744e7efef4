# libFuzzer targets for the readers of outside bytes (docs/reliability.md, "Fuzzing and sanitizers").
#
# faultline_add_fuzz_target(<name> SOURCE <fuzz_x.cpp> LIBS <libs...> [MAX_LEN <bytes>] [CORPUS <dir>])
#
#   <fuzz_x.cpp> defines LLVMFuzzerTestOneInput. In every build with tests, it is compiled into
#   fuzz_replay_<name> (a plain main, no libFuzzer) and the CTest test fuzz_regressions.<name> runs it over
#   every file of tests/<concern>/fuzz_regressions/<name>/ and of the seed corpus, so a crash once found
#   stays fixed. With -DFAULTLINE_FUZZ=ON (clang), it is also linked with libFuzzer into fuzz_<name>, part of
#   the target faultline_fuzz_targets, and listed in <build>/fuzz_targets.txt for scripts/fuzz.sh:
#   "<name> <binary> <corpus dir> <regressions dir> <max_len>".
#   CORPUS defaults to tests/<concern>/fuzz_corpus/<name>/; MAX_LEN (default 4096) bounds the input size.

option(FAULTLINE_FUZZ "Build the libFuzzer targets (clang only; every target instrumented, see scripts/fuzz.sh)" OFF)
set(FAULTLINE_FUZZ_LIST ${CMAKE_BINARY_DIR}/fuzz_targets.txt)
add_custom_target(faultline_fuzz_replays)  # every fuzz_replay_<name> (scripts/sanitize.sh builds them)
if(FAULTLINE_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "FAULTLINE_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
  endif()
  # Every library a fuzz target links is instrumented for coverage and checked by ASan and UBSan, so the
  # fuzzer is steered by the reader's own branches. Only the fuzz targets themselves link libFuzzer's main.
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                      -fno-omit-frame-pointer
                      -fsanitize-ignorelist=${PROJECT_SOURCE_DIR}/tests/sanitizer_ignorelist.txt)
  add_link_options(-fsanitize=address,undefined)
  add_custom_target(faultline_fuzz_targets)
  file(WRITE ${FAULTLINE_FUZZ_LIST} "")
endif()

function(faultline_add_fuzz_target name)
  cmake_parse_arguments(ARG "" "SOURCE;MAX_LEN;CORPUS" "LIBS" ${ARGN})
  if(NOT ARG_MAX_LEN)
    set(ARG_MAX_LEN 4096)
  endif()
  if(NOT ARG_CORPUS)
    set(ARG_CORPUS ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_corpus/${name})
  endif()
  set(regressions ${CMAKE_CURRENT_SOURCE_DIR}/fuzz_regressions/${name})

  add_executable(fuzz_replay_${name} ${ARG_SOURCE} ${PROJECT_SOURCE_DIR}/tests/fuzz_replay_main.cpp)
  target_link_libraries(fuzz_replay_${name} PRIVATE ${ARG_LIBS})
  target_include_directories(fuzz_replay_${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  faultline_warnings(fuzz_replay_${name})
  add_dependencies(faultline_fuzz_replays fuzz_replay_${name})
  add_test(NAME fuzz_regressions.${name} COMMAND fuzz_replay_${name} ${regressions} ${ARG_CORPUS})
  set_tests_properties(fuzz_regressions.${name} PROPERTIES LABELS fuzz)

  if(FAULTLINE_FUZZ)
    add_executable(fuzz_${name} ${ARG_SOURCE})
    target_link_libraries(fuzz_${name} PRIVATE ${ARG_LIBS})
    target_include_directories(fuzz_${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
    target_link_options(fuzz_${name} PRIVATE -fsanitize=fuzzer)
    faultline_warnings(fuzz_${name})
    add_dependencies(faultline_fuzz_targets fuzz_${name})
    file(APPEND ${FAULTLINE_FUZZ_LIST}
         "${name} ${CMAKE_RUNTIME_OUTPUT_DIRECTORY}/fuzz_${name} ${ARG_CORPUS} ${regressions} ${ARG_MAX_LEN}\n")
  endif()
endfunction()
