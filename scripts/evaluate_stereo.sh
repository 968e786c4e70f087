#!/usr/bin/env bash
# Accuracy of orientation_stereo on a data set with ground truth (../shared/data/<set>, or one
# made by `hairmvs synthesize`), as issue notes report it. Makes a writable copy of the set's
# dense workspace in OUT (links to its images, masks and sparse model; its stereo/*.cfg
# copied), runs orientation_stereo there (both passes, orientation fields computed, the coarse
# data term kept), then evaluates the .geometric maps, the first estimates (.photometric maps)
# and the data term alone. Extra arguments go to orientation_stereo, e.g.
#   bash scripts/evaluate_stereo.sh ../shared/data/synth_handheld out/hh_photo \
#       --OrientationStereo.cost photometric
# OUT must not exist yet. Needs the built tool (bash scripts/build.sh hairmvs). The cost
# volumes (about 20 MiB a view: 0.6 GB for synth_straight_gantry) are removed once the data
# term is evaluated, so that a series of runs does not fill the disk; KEEP_COST_VOLUMES=1 keeps
# them in OUT/stereo/cost_volumes.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 SET_DIR OUT_DIR [orientation_stereo options...]" >&2
  exit 2
fi
SET=$(realpath "$1")
OUT=$2
shift 2
HAIRMVS=$(realpath -m "$(dirname "$0")/../build/src/cli/hairmvs")
[ -x "$HAIRMVS" ] || { echo "error: $HAIRMVS is missing: run bash scripts/build.sh hairmvs" >&2; exit 1; }
for d in "$SET/dense/images" "$SET/dense/sparse" "$SET/gt"; do
  [ -d "$d" ] || { echo "error: $d is missing (a data set: dense/ workspace and gt/)" >&2; exit 1; }
done
[ -e "$OUT" ] && { echo "error: $OUT exists; give a new folder" >&2; exit 1; }

mkdir -p "$OUT/stereo"
for d in images masks sparse; do
  if [ -e "$SET/dense/$d" ]; then ln -s "$SET/dense/$d" "$OUT/$d"; fi
done
# The configuration files, where the set has them (orientation_stereo reads them if present).
for cfg in "$SET"/dense/stereo/*.cfg; do
  if [ -f "$cfg" ]; then cp "$cfg" "$OUT/stereo/"; fi
done

start=$(date +%s)
"$HAIRMVS" orientation_stereo --workspace_path "$OUT" \
  --OrientationStereo.write_cost_volume 1 "$@" > "$OUT/orientation_stereo.log" 2>&1 ||
  { tail -20 "$OUT/orientation_stereo.log" >&2; exit 1; }
seconds=$(( $(date +%s) - start ))
# Runs one evaluation into its log; on failure the log's end is shown, not a silent exit.
evaluate() {
  local log=$1
  shift
  "$HAIRMVS" "$@" > "$log" 2>&1 || { tail -20 "$log" >&2; exit 1; }
}
evaluate "$OUT/evaluate_geometric.log" evaluate_depth --workspace_path "$OUT" \
  --ground_truth_path "$SET/gt" --max_points_3d_per_view 3000
evaluate "$OUT/evaluate_first_estimate.log" evaluate_depth --workspace_path "$OUT" \
  --ground_truth_path "$SET/gt" --max_points_3d_per_view 3000 --depth_type photometric \
  --output_path "$OUT/stereo/evaluation_first_estimate"
evaluate "$OUT/evaluate_data_term.log" evaluate_data_term --workspace_path "$OUT" \
  --ground_truth_path "$SET/gt"
if [ "${KEEP_COST_VOLUMES:-0}" != 1 ]; then rm -rf "$OUT/stereo/cost_volumes"; fi

header=$(grep -m1 '^view ' "$OUT/evaluate_geometric.log")
echo "orientation_stereo on $SET ($*): ${seconds} s wall," \
  "$(grep -m1 -o 'Peak resident memory: .*' "$OUT/orientation_stereo.log" || echo 'peak memory: see log')"
echo "$header"
echo "$(grep '^overall' "$OUT/evaluate_geometric.log")   .geometric"
echo "$(grep '^overall' "$OUT/evaluate_first_estimate.log")   first estimate"
grep -m1 '^view ' "$OUT/evaluate_data_term.log"
echo "$(grep '^overall' "$OUT/evaluate_data_term.log")   data term alone"
echo "per view: $OUT/*.log; JSON: $OUT/stereo/evaluation*/"
