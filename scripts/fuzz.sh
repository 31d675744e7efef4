#!/usr/bin/env bash
# Builds the libFuzzer targets with clang in build-fuzz/ (-DFAULTLINE_FUZZ=ON: every library instrumented for
# coverage, ASan and UBSan; cmake/fuzz.cmake) and runs each for a bounded time.
# Usage: scripts/fuzz.sh [--seconds N] [--jobs J] [--seed S] [target ...]
#   --seconds N  run each target N seconds (default 60); every target in build-fuzz/fuzz_targets.txt unless named
#   --jobs J     run J targets at a time, one process each (default: nproc); FUZZ_BUILD_JOBS sets the build's -j
#   --seed S     libFuzzer's -seed (default: a new one each run). CI passes 1: from the same seeds and corpus the
#                same inputs come in the same order, so a commit's fuzz stage passes or fails the same way again
# build-fuzz/ is also the ASan+UBSan test tree of scripts/sanitize.sh asan (scripts/clang-tree.sh), so after that
# script the libraries are already built and only the fuzz targets' own sources compile and link here.
#
# Each target starts from its seed corpus and its regressions folder (read only) plus build-fuzz/corpus/<target>/
# (what earlier runs found; libFuzzer writes new inputs there only). Executions per target are printed and kept in
# build-fuzz/fuzz_summary.txt. A crash, leak, timeout or out-of-memory input is copied into the target's
# tests/<concern>/fuzz_regressions/<target>/ folder, where the normal build replays it (CTest fuzz_regressions.*),
# and the script exits 1 once every target has run.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=60
jobs="$(nproc)"
seed_flags=()
wanted=()
while (($#)); do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --seconds=*) seconds="${1#*=}"; shift ;;
    --jobs) jobs="$2"; shift 2 ;;
    --jobs=*) jobs="${1#*=}"; shift ;;
    --seed) seed_flags=(-seed="$2"); shift 2 ;;
    --seed=*) seed_flags=(-seed="${1#*=}"); shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) wanted+=("$1"); shift ;;
  esac
done

scripts/install-clang.sh
source scripts/clang-tree.sh
configure_clang_tree
# Named targets: only those are built (the list of targets comes from the configure step).
build_targets=(faultline_fuzz_targets)
if ((${#wanted[@]})); then
  build_targets=()
  for t in "${wanted[@]}"; do build_targets+=("fuzz_$t"); done
fi
cmake --build build-fuzz --target "${build_targets[@]}" -j"${FUZZ_BUILD_JOBS:-$(nproc)}"

summary=build-fuzz/fuzz_summary.txt
results=build-fuzz/fuzz_results
rm -rf "$results"
mkdir -p "$results"

# fuzz_one <name> <binary> <corpus> <regressions> <max_len>: one bounded run; writes its summary line to
# $results/<name> and exits non-zero when the target found a failing input.
fuzz_one() {
  local name="$1" binary="$2" corpus="$3" regressions="$4" max_len="$5"
  local work=build-fuzz/corpus/$name artifacts=build-fuzz/artifacts/$name log=build-fuzz/logs/$name.log
  mkdir -p "$work" "$artifacts" "$(dirname "$log")"
  local dirs=("$work" "$corpus")
  [[ -d "$regressions" ]] && dirs+=("$regressions")
  local status=0
  # -timeout: one input taking 25 s is a hang; -close_fd_mask=1 silences the readers' stdout, not the reports.
  "$binary" -max_total_time="$seconds" -max_len="$max_len" -rss_limit_mb=2048 -timeout=25 -close_fd_mask=1 \
    -print_final_stats=1 "${seed_flags[@]}" -artifact_prefix="$artifacts/" "${dirs[@]}" >"$log" 2>&1 || status=$?
  local execs rate units result=ok
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  units=$(find "$work" -type f | wc -l)
  if ((status != 0)); then
    result="FAILED (exit $status, log $log)"
    mkdir -p "$regressions"
    for f in "$artifacts"/*; do
      [[ -f "$f" ]] || continue
      cp "$f" "$regressions/"
      result+="; kept $regressions/$(basename "$f")"
    done
  fi
  printf '%-16s %12s %10s %8s  %s\n' "$name" "${execs:-?}" "${rate:-?}" "$units" "$result" >"$results/$name"
  if ((status != 0)); then
    grep -m1 -E "ERROR: (AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer|libFuzzer)|runtime error|property violated" \
      "$log" >>"$results/$name" || tail -5 "$log" >>"$results/$name"
    return 1
  fi
}

names=()
while read -r name binary corpus regressions max_len; do
  if ((${#wanted[@]})) && [[ " ${wanted[*]} " != *" $name "* ]]; then continue; fi
  names+=("$name")
  # At most $jobs targets at a time: each run is one single-threaded process.
  while (($(jobs -rp | wc -l) >= jobs)); do wait -n || true; done
  fuzz_one "$name" "$binary" "$corpus" "$regressions" "$max_len" &
done < build-fuzz/fuzz_targets.txt
wait || true

if ((${#names[@]} == 0)); then
  echo "fuzz.sh: no target matched ${wanted[*]}" >&2
  exit 2
fi
printf '%-16s %12s %10s %8s  %s\n' target executions exec/s corpus result | tee "$summary"
failed=0
for name in "${names[@]}"; do
  if [[ ! -f "$results/$name" ]]; then
    echo "$name: no result (the run did not finish)" | tee -a "$summary"
    failed=$((failed + 1))
    continue
  fi
  tee -a "$summary" <"$results/$name"
  grep -q FAILED "$results/$name" && failed=$((failed + 1))
done
if ((failed)); then
  echo "fuzz.sh: $failed target(s) found a failing input; fix the reader and keep the input as a regression" >&2
  exit 1
fi
