#!/usr/bin/env bash
# The simulated light pairs are plausible, not trivial (issue "host_sim"): with seed 1, the
# core's diagonal matcher on the library (noon-lamps) against the same track under another
# light and under the same light again neither fails nor is perfect; a light change costs the
# unprocessed baseline against the same-light reference; histogram equalisation beats no
# preprocessing on every light change. At the 2015 thesis's 32x16: at 12x10 (the default
# since issue 33) HE alone loses the morning pair to no preprocessing (61.7 against 69.7 %
# top-1), one reason the default there is HE then PN. Usage: sim_plausible.sh BIN_DIR WORK_DIR
set -euo pipefail
BIN=$1
WORK=$2
rm -rf "$WORK"
"$BIN/seqslam-sim" generate --scenario lights --lights noon-lamps,morning-lamps,dim --seed 1 \
  --size 32x16 --out "$WORK" > /dev/null
"$BIN/seqslam-sim" evaluate "$WORK" --methods none,he | tee "$WORK/table.md"
# Rows: | noon-lamps -> LIGHT | method | queries | top-1 % | R@100P | AUC | P / R |
awk -F'|' '
  NR > 2 {
    gsub(/ /, "", $2); gsub(/ /, "", $3)
    top1[$2 "," $3] = $5 + 0; auc[$2 "," $3] = $7 + 0; pairs[$2] = 1
  }
  END {
    bad = 0
    ref = "noon-lamps->noon-lamps"
    for (p in pairs) {
      if (top1[p ",he"] <= 10 || top1[p ",he"] >= 99.5) { print "FAIL: " p " HE top-1 " top1[p ",he"] " is trivial or failing"; bad = 1 }
      if (p == ref) continue
      if (top1[p ",none"] >= top1[ref ",none"]) { print "FAIL: " p ": the light change does not hurt the baseline"; bad = 1 }
      if (top1[p ",he"] <= top1[p ",none"] || auc[p ",he"] <= auc[p ",none"]) { print "FAIL: " p ": HE does not help"; bad = 1 }
    }
    if (length(pairs) != 3) { print "FAIL: expected 3 pairs"; bad = 1 }
    exit bad
  }' "$WORK/table.md"
echo "plausible: every pair neither fails nor is perfect; light changes hurt the baseline; HE helps"
