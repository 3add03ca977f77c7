#!/usr/bin/env bash
# Generates one simulator scenario set once and caches it (shared by route-eval.sh and
# tune-eval.sh): DIR counts as cached once its generation finished (DIR/.complete), so an
# interrupted run is generated again. Usage: scripts/sim-set.sh SIM SCENARIO SEED DIR
set -euo pipefail
sim=$1 scenario=$2 seed=$3 dir=$4
if [ -f "$dir/.complete" ] && [ -f "$dir/pairs.csv" ]; then exit 0; fi
[ -x "$sim" ] || { echo "sim-set: $sim missing: build the host tools first" >&2; exit 1; }
echo "generating $scenario, seed $seed (about 1-2 min) ..." >&2
rm -rf "$dir" "$dir.tmp"
"$sim" generate --scenario "$scenario" --seed "$seed" --out "$dir.tmp" > "$dir.log"
touch "$dir.tmp/.complete"
mv "$dir.tmp" "$dir"
