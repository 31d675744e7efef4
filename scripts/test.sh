#!/usr/bin/env bash
# Installs what is missing, builds everything and runs the whole test suite (what CI runs).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --with-browser
if [[ -f tests/mcap_js/package-lock.json && ( ! -d tests/mcap_js/node_modules/@mcap/core ||
      ! -d tests/mcap_js/node_modules/@foxglove/rosmsg2-serialization ) ]]; then
  (cd tests/mcap_js && npm ci --no-audit --no-fund --silent) || echo "test.sh: npm ci failed; the Node MCAP validation will be skipped"
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DFAULTLINE_WERROR="${FAULTLINE_WERROR:-OFF}" >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)" --timeout 900
