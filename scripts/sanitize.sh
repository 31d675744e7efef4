#!/usr/bin/env bash
# Sanitizer builds of the tests (docs/reliability.md, "Fuzzing and sanitizers"), with Debian's clang, -O1 -g and
# assertions on. Exit status is non-zero when a build fails, a sanitizer reports or a test fails.
# Usage: scripts/sanitize.sh asan [all] | tsan
#   asan      build-asan/, -fsanitize=address,undefined (UB fatal, leaks reported at exit): the suites of the
#             libraries that read outside bytes (common, transport, codec, dataset, scoring, bag, launch) and
#             every fuzz_regressions.* replay (fault schedules among them: the policy suite needs the whole
#             tool). This is what CI runs (docs/reliability.md says why not the whole suite).
#   asan all  the same build, every target, the whole CTest suite (as scripts/test.sh runs it on Release).
#   tsan      build-tsan/, -fsanitize=thread: the transport tests (sockets, zero-copy payloads released from
#             libzmq's I/O thread) and the runtime tests (player, injector with its fault policy, and sink loops in
#             threads of one process over the live transport).
set -euo pipefail
cd "$(dirname "$0")/.."

mode="${1:-asan}"
scope="${2:-}"
scripts/install-clang.sh
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi

configure() {  # configure <dir> <sanitizer flags>
  cmake -S . -B "$1" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
    -DCMAKE_CXX_FLAGS="$2 -fno-omit-frame-pointer -fsanitize-ignorelist=$PWD/tests/sanitizer_ignorelist.txt" \
    -DCMAKE_EXE_LINKER_FLAGS="$2" -DCMAKE_SHARED_LINKER_FLAGS="$2" -DFAULTLINE_BUILD_BENCH=OFF \
    "${launcher[@]}" >/dev/null
}

run_suites() {  # run_suites <dir> <gtest filter> <test executable>...
  local dir="$1" filter="$2"
  shift 2
  for t in "$@"; do
    echo "sanitize.sh: $mode $t"
    "$dir/bin/$t" --gtest_brief=1 --gtest_filter="$filter"
  done
}

case "$mode" in
  asan)
    configure build-asan "-fsanitize=address,undefined -fno-sanitize-recover=undefined"
    export ASAN_OPTIONS="detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1"
    export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
    if [[ "$scope" == all ]]; then
      cmake --build build-asan -j"$(nproc)"
      ctest --test-dir build-asan --output-on-failure -j"$(nproc)" --timeout 1800
    else
      suites=(faultline_common_test faultline_transport_test faultline_codec_test faultline_dataset_test
              faultline_scoring_test faultline_bag_test faultline_launch_test)
      cmake --build build-asan -j"$(nproc)" --target "${suites[@]}" faultline_fuzz_replays
      # The Cli* tests run build/bin/faultline, which this subset does not build (the whole tool would).
      run_suites build-asan "-*Cli*" "${suites[@]}"
      ctest --test-dir build-asan --output-on-failure -j"$(nproc)" -L fuzz
    fi
    ;;
  tsan)
    configure build-tsan "-fsanitize=thread"
    suites=(faultline_transport_test faultline_runtime_test)
    cmake --build build-tsan -j"$(nproc)" --target "${suites[@]}"
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp"
    run_suites build-tsan "*" "${suites[@]}"
    ;;
  *)
    echo "usage: scripts/sanitize.sh asan [all] | tsan" >&2
    exit 2
    ;;
esac
echo "sanitize.sh: $mode ${scope:+$scope }green"
