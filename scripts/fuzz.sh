#!/usr/bin/env bash
# Builds the libFuzzer targets with clang in build-fuzz/ (-DFAULTLINE_FUZZ=ON: every library instrumented for
# coverage, ASan and UBSan; cmake/fuzz.cmake) and runs each for a bounded time.
# Usage: scripts/fuzz.sh [--seconds N] [target ...]     (default: 60 s, every target in build-fuzz/fuzz_targets.txt)
# Named targets are the only ones built and run; FUZZ_BUILD_JOBS sets the build's -j (default: nproc).
#
# Each target starts from its seed corpus and its regressions folder (read only) plus build-fuzz/corpus/<target>/
# (what earlier runs found; libFuzzer writes new inputs there only). Executions per target are printed and kept in
# build-fuzz/fuzz_summary.txt. A crash, leak, timeout or out-of-memory input is copied into the target's
# tests/<concern>/fuzz_regressions/<target>/ folder, where the normal build replays it (CTest fuzz_regressions.*),
# and the script exits 1 once every target has run.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=60
wanted=()
while (($#)); do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --seconds=*) seconds="${1#*=}"; shift ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) wanted+=("$1"); shift ;;
  esac
done

scripts/install-clang.sh
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# -O1 -g with assertions on: fast enough to fuzz, exact stack traces.
cmake -S . -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DFAULTLINE_FUZZ=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DFAULTLINE_BUILD_BENCH=OFF \
  "${launcher[@]}" >/dev/null
# Named targets: only those are built (the list of targets comes from the configure step).
build_targets=(faultline_fuzz_targets)
if ((${#wanted[@]})); then
  build_targets=()
  for t in "${wanted[@]}"; do build_targets+=("fuzz_$t"); done
fi
cmake --build build-fuzz --target "${build_targets[@]}" -j"${FUZZ_BUILD_JOBS:-$(nproc)}"

summary=build-fuzz/fuzz_summary.txt
printf '%-16s %12s %10s %8s  %s\n' target executions exec/s corpus result | tee "$summary"
failed=0
ran=0
while read -r name binary corpus regressions max_len; do
  if ((${#wanted[@]})) && [[ " ${wanted[*]} " != *" $name "* ]]; then continue; fi
  ran=$((ran + 1))
  work=build-fuzz/corpus/$name
  artifacts=build-fuzz/artifacts/$name
  log=build-fuzz/logs/$name.log
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  dirs=("$work" "$corpus")
  [[ -d "$regressions" ]] && dirs+=("$regressions")
  status=0
  # -timeout: one input taking 25 s is a hang; -close_fd_mask=1 silences the readers' stdout, not the reports.
  "$binary" -max_total_time="$seconds" -max_len="$max_len" -rss_limit_mb=2048 -timeout=25 -close_fd_mask=1 \
    -print_final_stats=1 -artifact_prefix="$artifacts/" "${dirs[@]}" >"$log" 2>&1 || status=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  units=$(find "$work" -type f | wc -l)
  result=ok
  if ((status != 0)); then
    failed=$((failed + 1))
    result="FAILED (exit $status, log $log)"
    mkdir -p "$regressions"
    for f in "$artifacts"/*; do
      [[ -f "$f" ]] || continue
      cp "$f" "$regressions/"
      result+="; kept $regressions/$(basename "$f")"
    done
    grep -m1 -E "ERROR: (AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer|libFuzzer)|runtime error|property violated" \
      "$log" || tail -5 "$log"
  fi
  printf '%-16s %12s %10s %8s  %s\n' "$name" "${execs:-?}" "${rate:-?}" "$units" "$result" | tee -a "$summary"
done < build-fuzz/fuzz_targets.txt

if ((ran == 0)); then
  echo "fuzz.sh: no target matched ${wanted[*]}" >&2
  exit 2
fi
if ((failed)); then
  echo "fuzz.sh: $failed target(s) found a failing input; fix the reader and keep the input as a regression" >&2
  exit 1
fi
