#!/usr/bin/env bash
# Installs, builds and runs the main job on the default data set.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
DATA=${1:-../shared/data/synth_straight_gantry/dense}
./build/src/cli/hairmvs workspace_info --workspace_path "$DATA"
