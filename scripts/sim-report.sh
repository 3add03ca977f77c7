#!/usr/bin/env bash
# Reproduces the figures of docs/simulator.md: generates the scenarios with seed 1 into
# build/sim-report/ at 32x16 (the size the page was measured at, the default before issue
# 33) and evaluates the core's diagonal matcher (32x16, S = 30, W = 50,
# R = 10, threshold 0.85) with no preprocessing, HE and PN on every pair.
# Takes about 4 minutes on 2 cores. Needs `make tools` (or the host build) first.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/host/bin}
OUT=${OUT:-build/sim-report}
SEED=${SEED:-1}
mkdir -p "$OUT"
for scenario in default lights jump kidnapped novelty; do
  echo "== $scenario =="
  rm -rf "${OUT:?}/$scenario"
  start=$(date +%s%N)
  "$BIN/seqslam-sim" generate --scenario "$scenario" --seed "$SEED" --size 32x16 \
    --out "$OUT/$scenario"
  echo "generated in $(( ($(date +%s%N) - start) / 1000000 )) ms (wall)"
  "$BIN/seqslam-sim" evaluate "$OUT/$scenario" --markdown "$OUT/$scenario/table.md"
  echo
done
