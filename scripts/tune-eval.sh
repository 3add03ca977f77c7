#!/usr/bin/env bash
# Defaults by evidence (docs/accuracy.md, "Choosing the defaults: seqslam tune"; issue 33):
# `seqslam sweep` over every real pair (the corridor; Gardens Point's three pairs when
# ../shared/data/gardens_point or GARDENS_POINT is there) and the simulator's light pairs of
# seeds 1-3, on a grid of image size, preprocessing, S, W and matcher; then `seqslam tune`,
# each pair held out in turn, choosing by the area under the PR curve smoothed over the
# neighbouring S and W with each dataset weighing the same (the rule one answer cannot flip),
# and once more by recall at 100 % precision for comparison. The light sets are generated once
# and shared with `make route-eval` (build/route-eval/sim, about 1-2 min a seed); the sweep
# takes a few minutes on 2 cores and resumes where it stopped.
#   OUT=build/tune-eval BIN=build/host/bin scripts/tune-eval.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/host/bin}
OUT=${OUT:-build/tune-eval}
SIMDIR=${SIMDIR:-build/route-eval/sim}
GP=${GARDENS_POINT:-../shared/data/gardens_point}
S="$BIN/seqslam"
[ -x "$S" ] || { echo "tune-eval: $S missing: build the host tools first" >&2; exit 1; }
mkdir -p "$OUT" "$SIMDIR"
sizes=(32x16 25x20 12x10)
# The simulator's recordings are made at one image size: a light set per seed and size.
set_dir() { echo "$SIMDIR/lights-s$1-$2"; }
for seed in 1 2 3; do
  for size in "${sizes[@]}"; do
    scripts/sim-set.sh "$BIN/seqslam-sim" lights "$seed" "$(set_dir "$seed" "$size")" "$size"
  done
done
settings=(--preprocess he,pn,he-pn,none --seq-len 10,20,30 --window 10,25,50
          --matcher diagonal,slope)
C=tests/data/corridor
real=(--pair "$C/ref,$C/query,$C/ground_truth.csv")
if [ -d "$GP/day_left" ]; then
  for p in day_left,night_right day_right,night_right day_left,day_right; do
    real+=(--pair "$GP/${p%,*},$GP/${p#*,},$GP/ground_truth.csv")
  done
else
  echo "tune-eval: $GP not found: the corridor is the only real pair" >&2
fi
sizes_list=$(IFS=,; echo "${sizes[*]}")
"$S" sweep "${real[@]}" --size "$sizes_list" "${settings[@]}" --out "$OUT/real.csv" --quiet
for size in "${sizes[@]}"; do
  sim=()
  for seed in 1 2 3; do sim+=(--pairs "$(set_dir "$seed" "$size")/pairs.csv"); done
  "$S" sweep "${sim[@]}" --size "$size" "${settings[@]}" --out "$OUT/sim-$size.csv" --quiet
done
# One pair whatever the size its recordings were made at: lights-sN-WxH/ -> lights-sN/.
{
  head -n 1 "$OUT/real.csv"
  tail -n +2 -q "$OUT/real.csv"
  for size in "${sizes[@]}"; do
    tail -n +2 -q "$OUT/sim-$size.csv" | sed -E 's#/lights-s([0-9]+)-[0-9]+x[0-9]+/#/lights-s\1/#g'
  done
} > "$OUT/sweep.csv"
# Against today's defaults (the settings table's), and against the defaults before issue 33,
# which the rule replaced: the rule's objective is the worst gain over the default it is given.
before="32x16,he,30,50,10,0.85,0,diagonal,mad"
"$S" tune "$OUT/sweep.csv" --out "$OUT/tune.md"
"$S" tune "$OUT/sweep.csv" --default "$before" --out "$OUT/tune-before.md"
"$S" tune "$OUT/sweep.csv" --default "$before" --objective mean --measure recall-at-100 \
  --no-smoothing --no-dataset-balance --out "$OUT/tune-recall.md"
cat "$OUT/tune.md"
echo
echo "(against the defaults before issue 33, $before: $OUT/tune-before.md)"
grep -E "^Stability|^Worst" "$OUT/tune-before.md"
echo
echo "(the rule before issue 33, the best mean recall at 100 % precision: $OUT/tune-recall.md)"
grep -E "^Stability|^Worst" "$OUT/tune-recall.md"
