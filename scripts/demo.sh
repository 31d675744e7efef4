#!/usr/bin/env bash
# The main job: installs what is missing, builds the tool and the nodes (not the tests), generates the
# embedded synthetic nuScenes dataset if absent (data/synth), and runs the RoboBEV benchmark live through
# the nodes (reduced matrix: clean + 8 corruptions at mid level). Extra arguments go to
# `faultline benchmark` (e.g. --full, --seeds 3).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh --tools
exec build/bin/faultline benchmark --out out/benchmark --synth-dir data/synth "$@"
