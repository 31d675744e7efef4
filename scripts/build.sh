#!/usr/bin/env bash
# Installs what is missing and builds Release into build/ (bin/faultline and every node land in build/bin).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
