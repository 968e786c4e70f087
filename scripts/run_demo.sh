#!/usr/bin/env bash
# The main job, for a new user: installs the Debian packages, builds hairmvs, synthesises the
# default data set (rendered hair with exact ground truth), runs the whole pipeline on it
# (orientation fields, orientation stereo, template fusion) and evaluates the depth maps and
# the mesh against the ground truth. Everything goes to ./out/demo (override: $1).
set -euo pipefail
# $1 is taken from where the script is called, before it moves to the repository.
DEFAULT_OUT=$(realpath -m "$(dirname "$0")/../out/demo")
OUT=$(realpath -m "${1:-$DEFAULT_OUT}")
cd "$(dirname "$0")/.."
# Only the command-line tool: the tests and benchmarks are built by scripts/run_tests.sh.
bash scripts/build.sh hairmvs
HAIRMVS=./build/src/cli/hairmvs
start=$(date +%s)
# A previous demo's output (marked by the demo itself with .hairmvs_demo) or an empty folder is
# replaced; any other folder is left alone, a data set of one's own (which has gt/meta.json as
# the demo's does) included. The default folder, ./out/demo, is the demo's own: replaced too
# where an older demo made it without the mark.
MARK=.hairmvs_demo
if [ -e "$OUT" ]; then
  if [ -f "$OUT/$MARK" ] || [ -z "$(ls -A "$OUT")" ] ||
     { [ "$OUT" = "$DEFAULT_OUT" ] && [ -f "$OUT/gt/meta.json" ]; }; then
    rm -rf "$OUT"
  else
    echo "run_demo.sh: $OUT exists and is not a previous demo's output (no $MARK);" \
         "give another folder" >&2
    exit 1
  fi
fi
# Marked first, so that a run stopped in the synthesis leaves a folder the next run replaces.
mkdir -p "$OUT"
echo "made by scripts/run_demo.sh, which replaces this folder on its next run" > "$OUT/$MARK"
# The generator's defaults (960 x 640, 100 000 strands): one T group of 4 views of curly hair.
$HAIRMVS synthesize --output_path "$OUT" --style curly --rig gantry --num_groups 1
$HAIRMVS pipeline --workspace_path "$OUT/dense" --ground_truth_path "$OUT/gt"
echo "demo: synthesis + pipeline + evaluation in $(( $(date +%s) - start )) s; outputs in $OUT/dense"
