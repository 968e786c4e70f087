#!/usr/bin/env bash
# The main job, for a new user: installs the Debian packages, builds hairmvs, synthesises the
# default data set (rendered hair with exact ground truth), runs the whole pipeline on it
# (orientation fields, orientation stereo, template fusion) and evaluates the depth maps and
# the mesh against the ground truth. Everything goes to ./out/demo (override: $1).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
OUT=${1:-out/demo}
HAIRMVS=./build/src/cli/hairmvs
start=$(date +%s)
rm -rf "$OUT"
# Denser hair than the generator's quick default: sparse, see-through hair leaves the
# sideways view pairs little orientation texture to match.
$HAIRMVS synthesize --output_path "$OUT" --width 960 --num_strands 40000
$HAIRMVS pipeline --workspace_path "$OUT/dense" --ground_truth_path "$OUT/gt"
echo "demo: synthesis + pipeline + evaluation in $(( $(date +%s) - start )) s; outputs in $OUT/dense"
