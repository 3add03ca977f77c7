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
for seed in 1 2 3; do
  scripts/sim-set.sh "$BIN/seqslam-sim" lights "$seed" "$SIMDIR/lights-s$seed"
done
C=tests/data/corridor
pairs=(--pair "$C/ref,$C/query,$C/ground_truth.csv")
if [ -d "$GP/day_left" ]; then
  for p in day_left,night_right day_right,night_right day_left,day_right; do
    pairs+=(--pair "$GP/${p%,*},$GP/${p#*,},$GP/ground_truth.csv")
  done
else
  echo "tune-eval: $GP not found: the corridor is the only real pair" >&2
fi
for seed in 1 2 3; do pairs+=(--pairs "$SIMDIR/lights-s$seed/pairs.csv"); done
grid=(--size 32x16,25x20,12x10 --preprocess he,pn,he-pn,none --seq-len 10,20,30
      --window 10,25,50 --matcher diagonal,slope)
"$S" sweep "${pairs[@]}" "${grid[@]}" --out "$OUT/sweep.csv" --quiet
"$S" tune "$OUT/sweep.csv" --out "$OUT/tune.md"
"$S" tune "$OUT/sweep.csv" --measure recall-at-100 --no-smoothing --no-dataset-balance \
  --out "$OUT/tune-recall.md"
cat "$OUT/tune.md"
echo
echo "(by recall at 100 % precision, each setting alone, a plain mean: $OUT/tune-recall.md)"
grep -E "^Stability|^Worst" "$OUT/tune-recall.md"
