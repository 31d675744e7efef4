#!/usr/bin/env bash
# Installs what is missing and builds Release into build/ (bin/faultline and every node land in build/bin).
# Usage: scripts/build.sh [--tools]   --tools builds only the faultline tool, the nodes and the Python client's
#                                      message modules (no tests, no benchmarks): what scripts/demo.sh needs.
set -euo pipefail
cd "$(dirname "$0")/.."
targets=()
if [[ "${1:-}" == "--tools" ]]; then targets=(--target faultline_tools); fi
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" "${targets[@]}"
