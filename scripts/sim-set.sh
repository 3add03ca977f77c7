#!/usr/bin/env bash
# Generates one simulator scenario set once and caches it (shared by route-eval.sh,
# tune-eval.sh and confidence-eval.sh): DIR counts as cached once its generation finished at
# the wanted image size (DIR/.complete holds "size=WxH"), so an interrupted run, or a set made
# at another size (an older default), is generated again.
# Usage: scripts/sim-set.sh SIM SCENARIO SEED DIR [SIZE]   (SIZE: the simulator's default)
set -euo pipefail
sim=$1 scenario=$2 seed=$3 dir=$4
[ -x "$sim" ] || { echo "sim-set: $sim missing: build the host tools first" >&2; exit 1; }
size=${5:-$("$sim" generate --help | sed -n 's/^ *--size TEXT=\([0-9]*x[0-9]*\).*/\1/p')}
[ -n "$size" ] || { echo "sim-set: cannot read the simulator's default size" >&2; exit 1; }
if [ -f "$dir/pairs.csv" ] && [ "$(cat "$dir/.complete" 2>/dev/null)" = "size=$size" ]; then
  exit 0
fi
echo "generating $scenario, seed $seed, $size (about 1-2 min) ..." >&2
rm -rf "$dir" "$dir.tmp"
"$sim" generate --scenario "$scenario" --seed "$seed" --size "$size" --out "$dir.tmp" > "$dir.log"
echo "size=$size" > "$dir.tmp/.complete"
mv "$dir.tmp" "$dir"
