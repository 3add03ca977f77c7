#!/usr/bin/env bash
# make demo: the firmware application on simulated runs of the lab.
#
#   1. seqslam-sim generates (once; cached by seed and simulator build) a library run under
#      one light and a query run under another, with ground truth (docs/simulator.md);
#   2. the firmware (build/host/bin/seqslam-firmware, the head board's app.cpp built for the
#      PC) teaches the library from the first run's replay on one card image,
#   3. then repeats on the second run's replay on a second card holding that library,
#   4. `seqslam results --ground-truth` scores its localisations,
#   5. and `seqslam report` writes the HTML report of the same pair (build/demo/report.html).
#
# Environment: SEED (default 1), LIBRARY_LIGHT (noon-lamps), QUERY_LIGHT (morning-lamps),
# OUT (build/demo), BIN (build/host/bin), SIZE (unset: the run configuration's default image
# size, which the simulator renders at and the tools take from the recordings).
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/host/bin}
OUT=${OUT:-build/demo}
SEED=${SEED:-1}
LIBRARY_LIGHT=${LIBRARY_LIGHT:-noon-lamps}
QUERY_LIGHT=${QUERY_LIGHT:-morning-lamps}
SIZE=${SIZE:-}
size_option=()
[ -z "$SIZE" ] || size_option=(--size "$SIZE")
SIM="$OUT/sim"
LIB="$SIM/loop_$LIBRARY_LIGHT.dream"
QUERY="$SIM/loop_$QUERY_LIGHT.dream"
TRUTH="$SIM/loop_$QUERY_LIGHT.gt.csv"

mkdir -p "$OUT"
stamp="seed=$SEED size=${SIZE:-default} lights=$LIBRARY_LIGHT,$QUERY_LIGHT sim=$(sha256sum "$BIN/seqslam-sim" | cut -c1-16)"
if [ ! -f "$SIM/stamp" ] || [ "$(cat "$SIM/stamp")" != "$stamp" ]; then
  rm -rf "$SIM"
  echo "== simulating the library and query runs (seqslam-sim generate) =="
  "$BIN/seqslam-sim" generate --scenario default --out "$SIM" --seed "$SEED" "${size_option[@]}" \
    --library-light "$LIBRARY_LIGHT" --lights "$QUERY_LIGHT"
  echo "$stamp" > "$SIM/stamp"
else
  echo "== simulated runs: reusing $SIM (same seed and simulator) =="
fi

echo
echo "== teaching: the firmware replays $(basename "$LIB") =="
"$BIN/seqslam" disk create "$OUT/teach.img" --file config:4K --file "replay::$LIB" \
  --file library:1M --file library.img:4M > /dev/null
"$BIN/seqslam" config write "$OUT/teach.img" --modes teach "${size_option[@]}" > /dev/null
"$BIN/seqslam-firmware" --disk "$OUT/teach.img" > "$OUT/teach.log"
tail -n 12 "$OUT/teach.log" | sed 's/^/  /'
"$BIN/seqslam" disk export "$OUT/teach.img" library "$OUT/library.bin" > /dev/null
"$BIN/seqslam" disk export "$OUT/teach.img" library.img "$OUT/library.img.bin" > /dev/null

echo
echo "== repeating: the firmware replays $(basename "$QUERY") against that library =="
"$BIN/seqslam" disk create "$OUT/repeat.img" --file config:4K --file "replay::$QUERY" \
  --file "library::$OUT/library.bin" --file "library.img::$OUT/library.img.bin" \
  --file results:1M --file queries:256K > /dev/null
"$BIN/seqslam" config write "$OUT/repeat.img" --modes repeat "${size_option[@]}" > /dev/null
"$BIN/seqslam-firmware" --disk "$OUT/repeat.img" > "$OUT/repeat.log"
tail -n 12 "$OUT/repeat.log" | sed 's/^/  /'

echo
echo "== result: the firmware's localisations against the simulator's ground truth =="
"$BIN/seqslam" results "$OUT/repeat.img" --ground-truth "$TRUTH" --json "$OUT/result.json"
echo
echo "== report: the same pair evaluated on the PC (seqslam report; none and HE overlaid) =="
"$BIN/seqslam" report "$LIB" "$QUERY" --ground-truth "$TRUTH" "${size_option[@]}" --compare none,he \
  --title "make demo: $LIBRARY_LIGHT -> $QUERY_LIGHT (seed $SEED)" --out "$OUT/report.html"
echo
echo "logs: $OUT/teach.log, $OUT/repeat.log; figures: $OUT/result.json"
echo "open $OUT/report.html in a browser (self-contained, works offline)"
