#!/usr/bin/env bash
# Speed of `seqslam eval` (issue "seqslam host tool"): two runs of 3 600 places each at 32x16
# (about 13 million image comparisons), HE, S = 30 (the settings docs/seqslam_eval.md measured
# with, before issue 33), input loading included, on all cores.
# The 3 600-place runs are the simulator's two ~450-place demo runs (noon-lamps and
# morning-lamps), each repeated 8 times into a reduced dream recording (the figures are
# about speed; repeated places make the precision meaningless). Prints the wall time of
# three runs, the evaluation's own breakdown, its SIMD target and peak memory, then the SAD
# kernel's throughput per SIMD target (build/host/bin/seqslam_bench_sad, Google Benchmark).
# Needs `make tools`. Results: docs/seqslam_eval.md "Speed".
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/host/bin}
OUT=${OUT:-build/bench-eval}
mkdir -p "$OUT"
if [ ! -f "$OUT/lib.dream" ] || [ ! -f "$OUT/query.dream" ] || [ ! -f "$OUT/noon-lamps.once" ]; then
  "$BIN/seqslam-sim" generate --scenario default --lights morning-lamps --size 32x16 \
    --out "$OUT/sim" > /dev/null
  for run in noon-lamps morning-lamps; do
    rm -rf "$OUT/$run"
    "$BIN/seqslam" convert dream-to-images "$OUT/sim/loop_$run.dream" "$OUT/$run" > /dev/null
    ls "$PWD/$OUT/$run"/*.png > "$OUT/$run.once"
    awk '{ line[NR] = $0 } END { for (i = 0; i < 3600; i++) print line[i % NR + 1] }' \
      "$OUT/$run.once" > "$OUT/$run.txt"
  done
  "$BIN/seqslam" convert images-to-dream "$OUT/noon-lamps.txt" "$OUT/lib.dream" --size 32x16 > /dev/null
  "$BIN/seqslam" convert images-to-dream "$OUT/morning-lamps.txt" "$OUT/query.dream" --size 32x16 > /dev/null
fi
echo "seqslam eval, 3600 x 3600 places, 32x16, HE, S=30, W=50, $(nproc) cores:"
best=""
for i in 1 2 3; do
  start=$(date +%s%N)
  "$BIN/seqslam" eval "$OUT/lib.dream" "$OUT/query.dream" --ground-truth identity:1 --preprocess he --quiet \
    --json "$OUT/eval.json"
  ms=$(( ($(date +%s%N) - start) / 1000000 ))
  echo "  run $i: $ms ms wall (process start to exit)"
  if [ -z "$best" ] || [ "$ms" -lt "$best" ]; then best=$ms; fi
done
sed -n 's/.*"timing_ms": \(.*\),$/  breakdown of the last run (ms): \1/p' "$OUT/eval.json"
sed -n 's/^  "host": \(.*\),$/  host of the last run: \1/p' "$OUT/eval.json"
echo "best: $best ms (target: at most 300 ms)"
echo
echo "SAD kernel, 64 x 3600 images at 32x16, one thread, per SIMD target this CPU runs:"
"$BIN/seqslam_bench_sad" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
  2>/dev/null | grep -E '^Benchmark|_median'

# A long route: 30 000 x 30 000 places (each run's ~450 places repeated), in bands of query
# rows (the whole matrix would be 3.6 GB). Then a 3 600-place prefix of the same recordings,
# banded and whole (--cache keeps the whole matrix), must give the same results.
if [ ! -f "$OUT/lib30k.dream" ] || [ ! -f "$OUT/query30k.dream" ]; then
  for run in noon-lamps morning-lamps; do
    awk '{ line[NR] = $0 } END { for (i = 0; i < 30000; i++) print line[i % NR + 1] }' \
      "$OUT/$run.once" > "$OUT/$run.30k.txt"
  done
  "$BIN/seqslam" convert images-to-dream "$OUT/noon-lamps.30k.txt" "$OUT/lib30k.dream" --size 32x16 > /dev/null
  "$BIN/seqslam" convert images-to-dream "$OUT/morning-lamps.30k.txt" "$OUT/query30k.dream" --size 32x16 > /dev/null
fi
echo
echo "seqslam eval, 30000 x 30000 places, 32x16, HE, S=30, W=50, automatic bands:"
start=$(date +%s%N)
"$BIN/seqslam" eval "$OUT/lib30k.dream" "$OUT/query30k.dream" --ground-truth identity:1 --preprocess he --quiet \
  --json "$OUT/eval30k.json"
echo "  $(( ($(date +%s%N) - start) / 1000000 )) ms wall (process start to exit)"
sed -n 's/.*"timing_ms": \(.*\),$/  breakdown (ms): \1/p' "$OUT/eval30k.json"
sed -n 's/^  "host": \(.*\),$/  host: \1/p' "$OUT/eval30k.json"
rm -rf "$OUT/cache"
for plan in banded whole; do
  extra=()
  [ "$plan" = whole ] && extra=(--cache "$OUT/cache")
  "$BIN/seqslam" eval "$OUT/lib30k.dream" "$OUT/query30k.dream" --ground-truth identity:1 --preprocess he --quiet \
    --library-range 0:3600 --query-range 0:3600 --json "$OUT/prefix_$plan.json" "${extra[@]}"
done
python3 - "$OUT/prefix_banded.json" "$OUT/prefix_whole.json" <<'EOF'
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
assert a["host"]["band_rows"] < b["host"]["band_rows"] == 3600, (a["host"], b["host"])
same = a["matches"] == b["matches"] and a["summary"] == b["summary"]
print("  prefix 3600 x 3600: bands of %d rows and the whole matrix give %s results"
      % (a["host"]["band_rows"], "the same" if same else "DIFFERENT"))
sys.exit(0 if same else 1)
EOF
