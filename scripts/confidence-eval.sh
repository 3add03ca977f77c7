#!/usr/bin/env bash
# Which confidence ranks best (docs/normalisation.md, "Which offset ranks best"): `seqslam eval
# --reference` on the corridor and the simulator's light pairs of seeds 1-3 at 32x16, with
# the defaults before issue 33 (HE, S 30, W 50) and the pick of the rule before it (PN, S 30,
# W 25), the settings docs/normalisation.md measured. Per pair: recall at 100 % precision of the
# double-precision reference under three offsets of the ratio best / runner-up (the same best
# places): the online running minimum (the core's rule), the batch global minimum (OpenSeqSLAM;
# not online) and the fixed offset (costs as stored), then how often each wins or loses against
# the core's rule. Top-1 is also given over the first and the last third of the answered
# queries: the online rule differs from the batch one only early in a run. The 32x16 light
# sets are shared with `make tune-eval` (build/route-eval/sim/lights-sN-32x16).
#   OUT=build/confidence-eval BIN=build/host/bin scripts/confidence-eval.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/host/bin}
OUT=${OUT:-build/confidence-eval}
SIMDIR=${SIMDIR:-build/route-eval/sim}
S="$BIN/seqslam"
[ -x "$S" ] || { echo "confidence-eval: $S missing: build the host tools first" >&2; exit 1; }
mkdir -p "$OUT" "$SIMDIR"
for seed in 1 2 3; do
  scripts/sim-set.sh "$BIN/seqslam-sim" lights "$seed" "$SIMDIR/lights-s$seed-32x16" 32x16
done
C=tests/data/corridor
pairs=("$C/ref,$C/query,$C/ground_truth.csv,corridor")
for seed in 1 2 3; do
  d="$SIMDIR/lights-s$seed-32x16"
  while IFS=, read -r lib query truth _; do
    pairs+=("$d/$lib,$d/$query,$d/$truth,s$seed ${query%.dream}")
  done < <(tail -n +2 "$d/pairs.csv")
done
settings=("he 30 50" "pn 30 25")
rm -f "$OUT"/*.json
for setting in "${settings[@]}"; do
  read -r pre seq window <<< "$setting"
  for pair in "${pairs[@]}"; do
    IFS=, read -r lib query truth name <<< "$pair"
    json="$OUT/${pre}-S${seq}-W${window}-${name// /_}.json"
    "$S" eval "$lib" "$query" --ground-truth "$truth" --size 32x16 --preprocess "$pre" \
      --seq-len "$seq" --window "$window" --reference --quiet --json "$json"
  done
done
python3 - "$OUT" "${settings[@]}" <<'PYEOF' | tee "$OUT/summary.md"
import glob, json, os, sys
out, settings = sys.argv[1], sys.argv[2:]
rules = [("online", "online (core)"), ("batch", "batch (not online)"), ("fixed_offset", "fixed")]
for setting in settings:
    pre, seq, window = setting.split()
    prefix = "%s-S%s-W%s-" % (pre, seq, window)
    print("\n%s, S %s, W %s: top-1 (all, first and last third of the answers) and recall at "
          "100 %% precision by rule (%%)\n" % (pre.upper(), seq, window))
    print("| pair | top-1 | first third | last third | " + " | ".join(r[1] for r in rules) + " |")
    print("| --- | --- | --- | --- | " + " | ".join("---" for _ in rules) + " |")
    diffs = {r[0]: [] for r in rules}
    for path in sorted(glob.glob(os.path.join(out, prefix + "*.json"))):
        doc = json.load(open(path))
        ref = doc["reference"]
        answered = [m for m in doc["matches"] if m["library"] >= 0]
        third = len(answered) // 3
        early = sum(m["correct"] for m in answered[:third]) / third
        late = sum(m["correct"] for m in answered[-third:]) / third
        fig = {"online": ref["recall_at_100_precision"]}
        for key in ("batch", "fixed_offset"):
            fig[key] = ref[key]["recall_at_100_precision"]
            assert ref[key]["same_place"] == ref["same_place"], path
        name = os.path.basename(path)[len(prefix):-5].replace("_", " ", 1)
        print("| %s | %.1f | %.1f | %.1f | " % (name, 100 * ref["top1"], 100 * early, 100 * late) +
              " | ".join("%.1f" % (100 * fig[r[0]]) for r in rules) + " |")
        for r in rules:
            diffs[r[0]].append(100 * (fig[r[0]] - fig["online"]))
    for r in rules[1:]:
        d = diffs[r[0]]
        print("\n%s against the core's rule: mean %+.1f points, better on %d, worse on %d of %d "
              "pairs, worst %+.1f" % (r[1], sum(d) / len(d), sum(x > 0 for x in d),
                                      sum(x < 0 for x in d), len(d), min(d)))
PYEOF
