#!/usr/bin/env bash
# The main job, for a new user: installs the Debian packages, builds hairmvs, synthesises the
# default data set (rendered hair with exact ground truth), runs the whole pipeline on it
# (orientation fields, orientation stereo, template fusion) and evaluates the depth maps and
# the mesh against the ground truth. Everything goes to ./out/demo (override: $1).
set -euo pipefail
cd "$(dirname "$0")/.."
# Only the command-line tool: the tests and benchmarks are built by scripts/run_tests.sh.
bash scripts/build.sh hairmvs
OUT=${1:-out/demo}
HAIRMVS=./build/src/cli/hairmvs
start=$(date +%s)
rm -rf "$OUT"
# The generator's defaults (960 x 640, 100 000 strands): one T group of 4 views of curly hair.
$HAIRMVS synthesize --output_path "$OUT" --style curly --rig gantry --num_groups 1
$HAIRMVS pipeline --workspace_path "$OUT/dense" --ground_truth_path "$OUT/gt"
echo "demo: synthesis + pipeline + evaluation in $(( $(date +%s) - start )) s; outputs in $OUT/dense"
