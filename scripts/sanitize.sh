#!/usr/bin/env bash
# Sanitizer builds of the tests (docs/reliability.md, "Fuzzing and sanitizers"), with Debian's clang, -O1 -g and
# assertions on. Exit status is non-zero when a build fails, a sanitizer reports or a test fails.
# Usage: scripts/sanitize.sh asan [all] | tsan           (SANITIZE_BUILD_JOBS sets the build's -j; default nproc;
#                                                       SANITIZE_SUITE_TIMEOUT a suite's limit, default 900 s)
#   asan      build-fuzz/, the clang tree shared with scripts/fuzz.sh (scripts/clang-tree.sh: every library, node
#             and test built with -fsanitize=fuzzer-no-link,address,undefined, UB fatal, leaks reported at exit):
#             the suites of the libraries that read outside bytes (common, transport, codec, dataset, scoring,
#             bag, launch, ros2), the fault policy and the runtime (player, injector and sink loops; the injector
#             pipeline tests live there), and every fuzz_regressions.* replay. What CI runs (docs/reliability.md
#             gives the measured cost of the rest).
#   asan all  the same tree, every target, the whole CTest suite (as scripts/test.sh runs it on Release): nightly.
#   tsan      build-tsan/, -fsanitize=thread: the transport tests (sockets, zero-copy payloads released from
#             libzmq's I/O thread) and the runtime tests (player, injector with its fault policy and its pipeline
#             tests, and sink loops in threads of one process over the live transport).
set -euo pipefail
cd "$(dirname "$0")/.."

mode="${1:-asan}"
scope="${2:-}"
jobs="${SANITIZE_BUILD_JOBS:-$(nproc)}"
scripts/install-clang.sh

run_suites() {  # run_suites <dir> <gtest filter> <test executable>...
  local dir="$1" filter="$2"
  shift 2
  for t in "$@"; do
    echo "sanitize.sh: $mode $t"
    # A hang fails this suite (as ctest's --timeout does in stage 1) instead of using up CI's time.
    if ! timeout -k 10 "${SANITIZE_SUITE_TIMEOUT:-900}" "$dir/bin/$t" --gtest_brief=1 --gtest_filter="$filter"; then
      echo "sanitize.sh: $mode $t failed (or ran over ${SANITIZE_SUITE_TIMEOUT:-900} s)" >&2
      return 1
    fi
  done
}

case "$mode" in
  asan)
    source scripts/clang-tree.sh
    configure_clang_tree
    export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
    if [[ "$scope" == all ]]; then
      cmake --build build-fuzz -j"$jobs"
      ctest --test-dir build-fuzz --output-on-failure -j"$(nproc)" --timeout 1800
    else
      suites=(faultline_common_test faultline_transport_test faultline_codec_test faultline_dataset_test
              faultline_scoring_test faultline_bag_test faultline_launch_test faultline_ros2_test
              faultline_runtime_test)
      cmake --build build-fuzz -j"$jobs" --target "${suites[@]}" faultline_fuzz_replays
      # The Cli* tests run build-fuzz/bin/faultline, which this subset does not build (the whole tool would).
      run_suites build-fuzz "-*Cli*" "${suites[@]}"
      ctest --test-dir build-fuzz --output-on-failure -j"$(nproc)" -L fuzz
    fi
    ;;
  tsan)
    launcher=()
    if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
    flags="-fsanitize=thread"
    cmake -S . -B build-tsan -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
      -DCMAKE_CXX_FLAGS="$flags -fno-omit-frame-pointer -fsanitize-ignorelist=$PWD/tests/sanitizer_ignorelist.txt" \
      -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags" -DFAULTLINE_BUILD_BENCH=OFF \
      "${launcher[@]}" >/dev/null
    suites=(faultline_transport_test faultline_runtime_test)
    cmake --build build-tsan -j"$jobs" --target "${suites[@]}"
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp"
    run_suites build-tsan "*" "${suites[@]}"
    ;;
  *)
    echo "usage: scripts/sanitize.sh asan [all] | tsan" >&2
    exit 2
    ;;
esac
echo "sanitize.sh: $mode ${scope:+$scope }green"
