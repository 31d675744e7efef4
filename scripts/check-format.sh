#!/usr/bin/env bash
# Checks that every tracked C++ source follows .clang-format (clang-format 14, Debian's clang-format package).
# Usage: scripts/check-format.sh [--fix]
#   (no option)  clang-format --dry-run --Werror over every tracked .cpp/.hpp/.h under lib nodes tests bench
#                clients msgs; prints each file that differs and exits 1 if any does, 0 if none
#   --fix        rewrites the files that differ in place (clang-format -i) and lists them
# Vendored or third-party code (third_party/, vendor/, external/, node_modules/) and fuzz inputs (fuzz_corpus/,
# fuzz_regressions/: bytes, not sources) are left alone. CLANG_FORMAT names another binary (default clang-format-14).
set -euo pipefail
cd "$(dirname "$0")/.."

fix=0
case "${1:-}" in
  "") ;;
  --fix) fix=1 ;;
  -h|--help) sed -n '2,8p' "$0"; exit 0 ;;
  *) echo "check-format.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
esac

tool="${CLANG_FORMAT:-clang-format-14}"
if ! command -v "$tool" >/dev/null; then
  echo "check-format.sh: $tool not found (apt-get install clang-format-14, or set CLANG_FORMAT)" >&2
  exit 2
fi
# The project's style was set with clang-format 14; another major version formats some constructs differently.
if ! "$tool" --version | grep -q 'version 14\.'; then
  echo "check-format.sh: $tool is not clang-format 14: $("$tool" --version)" >&2
  exit 2
fi

files=()
while IFS= read -r -d '' f; do
  case "$f" in
    */third_party/*|*/vendor/*|*/external/*|*/node_modules/*|*/fuzz_corpus/*|*/fuzz_regressions/*) continue ;;
  esac
  files+=("$f")
done < <(git ls-files -z -- 'lib/*.cpp' 'lib/*.hpp' 'lib/*.h' 'nodes/*.cpp' 'nodes/*.hpp' 'nodes/*.h' \
           'tests/*.cpp' 'tests/*.hpp' 'tests/*.h' 'bench/*.cpp' 'bench/*.hpp' 'bench/*.h' \
           'clients/*.cpp' 'clients/*.hpp' 'clients/*.h' 'msgs/*.cpp' 'msgs/*.hpp' 'msgs/*.h')

existing=()
for f in "${files[@]}"; do
  [[ -f "$f" ]] && existing+=("$f")  # a file deleted in the work tree but still in the index is skipped
done
differing() {  # prints the files of "${existing[@]}" that differ; one clang-format process names each of them
  ((${#existing[@]})) || return 0
  "$tool" --style=file --dry-run --Werror "${existing[@]}" 2>&1 |
    sed -n 's/^\(.*\):[0-9][0-9]*:[0-9][0-9]*: error: code should be clang-formatted.*/\1/p' | sort -u
}

mapfile -t differ < <(differing)
if ((${#differ[@]} == 0)); then
  echo "check-format.sh: ${#existing[@]} files follow .clang-format"
  exit 0
fi
if ((fix)); then
  # clang-format 14 is not idempotent on a few files (a second pass changes them again): format until stable.
  changed=("${differ[@]}")
  for pass in 1 2 3; do
    "$tool" --style=file -i "${differ[@]}"
    mapfile -t differ < <(differing)
    ((${#differ[@]} == 0)) && break
  done
  printf 'reformatted %s\n' "${changed[@]}"
  if ((${#differ[@]})); then
    printf '%s\n' "${differ[@]}"
    echo "check-format.sh: ${#differ[@]} files still differ after 3 passes of clang-format -i" >&2
    exit 1
  fi
  echo "check-format.sh: reformatted ${#changed[@]} of ${#existing[@]} files"
  exit 0
fi
printf '%s\n' "${differ[@]}"
echo "check-format.sh: ${#differ[@]} of ${#existing[@]} files differ from .clang-format (scripts/check-format.sh --fix rewrites them)" >&2
exit 1
