#!/usr/bin/env bash
# The head board's route search against the full search (docs/accuracy.md, "The board's route
# search against the full search"): the simulator's `lights`, `kidnapped` and `jump` scenarios
# for seeds 1, 2, 3 (generated once, cached under $OUT/sim), every pair evaluated with
# `seqslam eval --search full` and `--search route` (the defaults: 12x10, HE then PN, S = 30,
# W = 50, R = 10, threshold 0.85; the route search with the firmware's defaults; SIZE and
# PREPROCESS choose another image size and preprocessing, e.g. SIZE=32x16 PREPROCESS=he for
# the defaults before issue 33, with sets of their own, $OUT/sim/SCENARIO-sN-SIZE), then per
# pair:
#  - top-1, recall at 100 % precision, AUC-PR, precision / recall at the threshold of both
#    searches and their differences (route - full, in points);
#  - agreement: (a) over the queries the full search localises, the fraction where the route
#    search answers the same place (and within +-1 place); (b) the same over every query both
#    answer; (c) over the queries both localise;
#  - kidnapped and jump pairs: every discontinuity of the true library place (the middle of
#    the ground truth's correct places moves by more than 5 places more or less than the
#    queries in between; also the run's start when it is not the library's first place, where
#    the route search's prediction begins), and for each search the places from it to the
#    first correct localised answer, and the wrong localised answers in between.
# Printed as Markdown tables and written to $OUT/summary.json. Needs the host tools
# (cmake --build --preset host --target seqslam-cli seqslam-sim) and python3 (standard
# library only). Generating the nine scenario sets takes 6-15 minutes on 2 cores; the
# evaluations about 1 s a pair.
#   SEEDS="1 2 3" OUT=build/route-eval BIN=build/host/bin [SIZE=WxH] [PREPROCESS=NAME] \
#     [ROUTE_OPTIONS="--lost-after N ..."] scripts/route-eval.sh
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-build/host/bin}
OUT=${OUT:-build/route-eval}
SEEDS=${SEEDS:-1 2 3}
SCENARIOS=${SCENARIOS:-lights kidnapped jump}
SIZE=${SIZE:-}
PREPROCESS=${PREPROCESS:-}
# More settings for the route search alone, e.g. ROUTE_OPTIONS="--lost-after 60".
ROUTE_OPTIONS=${ROUTE_OPTIONS:-}
settings=()
[ -z "$PREPROCESS" ] || settings=(--preprocess "$PREPROCESS")
S="$BIN/seqslam"
SIM="$BIN/seqslam-sim"
[ -x "$S" ] || { echo "route-eval: $S missing: build the host tools first" >&2; exit 1; }
mkdir -p "$OUT/sim" "$OUT/eval"

# The scenario sets: a directory counts as cached once its generation finished (.complete).
for seed in $SEEDS; do
  for scenario in $SCENARIOS; do
    scripts/sim-set.sh "$SIM" "$scenario" "$seed" "$OUT/sim/$scenario-s$seed${SIZE:+-$SIZE}" $SIZE
  done
done

# Both searches on every pair; the list of evaluations for the summary.
list="$OUT/eval/pairs.tsv"
: > "$list"
for seed in $SEEDS; do
  for scenario in $SCENARIOS; do
    dir="$OUT/sim/$scenario-s$seed${SIZE:+-$SIZE}"
    tail -n +2 "$dir/pairs.csv" | while IFS=, read -r library query truth description; do
      [ -n "$library" ] || continue
      name="$scenario-s$seed-${query%.dream}"
      for search in full route; do
        extra=()
        [ "$search" = full ] || read -r -a extra <<< "$ROUTE_OPTIONS"
        "$S" eval "$dir/$library" "$dir/$query" --ground-truth "$dir/$truth" --search "$search" \
          "${settings[@]}" "${extra[@]}" --quiet --json "$OUT/eval/$name.$search.json"
      done
      printf '%s\t%s\t%s\t%s\t%s\n' "$scenario" "$seed" "$description" "$dir/$truth" \
        "$OUT/eval/$name" >> "$list"
    done
  done
done

python3 - "$list" "$OUT/summary.json" <<'EOF'
import json, sys

list_file, out_file = sys.argv[1], sys.argv[2]
JUMP = 5  # places: a discontinuity of the true library place

def true_places(gt_file):
    """Per query: the middle of its correct library places (None: no true match)."""
    places = {}
    with open(gt_file) as f:
        next(f)
        for line in f:
            line = line.strip()
            if not line:
                continue
            q, refs = line.split(",", 1)
            refs = [int(r) for r in refs.split()]
            places[int(q)] = sum(refs) / len(refs) if refs else None
    return places

def events(places, queries, library_size, start):
    """Queries where the true place jumps; the run's start if it is not `start`."""
    out = []
    prev = None
    for q in range(queries):
        t = places.get(q)
        if t is None:
            continue
        if prev is None:
            if abs(t - start - q) > JUMP:
                out.append({"query": q, "kind": "start", "from": start, "to": round(t)})
        elif abs(t - prev[1] - (q - prev[0])) > JUMP:
            wrap = prev[1] >= library_size - 1 - JUMP and t <= JUMP
            out.append({"query": q, "kind": "library wrap" if wrap else "jump",
                        "from": round(prev[1]), "to": round(t)})
        prev = (q, t)
    return out

def recovery(matches, first, end):
    """Places from `first` to the first correct localised answer before `end`, and the wrong
    localised answers before it (or before `end` if none)."""
    wrong = 0
    for q in range(first, end):
        m = matches[q]
        if m["accepted"] and m["correct"]:
            return q - first, wrong
        if m["accepted"] and not m["correct"]:
            wrong += 1
    return None, wrong

def pct(x):
    return 100.0 * x

rows = []
with open(list_file) as f:
    for line in f:
        scenario, seed, description, gt, base = line.rstrip("\n").split("\t")
        full = json.load(open(base + ".full.json"))
        route = json.load(open(base + ".route.json"))
        fm, rm = full["matches"], route["matches"]
        assert len(fm) == len(rm)
        n = len(fm)
        library_size = full["library"]["images"]
        row = {"scenario": scenario, "seed": int(seed), "pair": description,
               "queries": full["summary"]["queries"]}
        assert route["summary"]["queries"] == row["queries"]
        for key in ["top1", "recall_at_100_precision", "auc_pr", "precision", "recall",
                    "accepted"]:
            row[key] = {"full": full["summary"][key], "route": route["summary"][key],
                        "difference": route["summary"][key] - full["summary"][key]}
        row["within_1_point"] = {
            k: abs(row[k]["difference"]) <= 0.01 + 1e-9 for k in ["top1", "recall_at_100_precision"]}
        def agree(sel):
            idx = [q for q in range(n) if sel(q)]
            same = sum(1 for q in idx if rm[q]["library"] == fm[q]["library"])
            near = sum(1 for q in idx
                       if rm[q]["library"] >= 0 and abs(rm[q]["library"] - fm[q]["library"]) <= 1)
            return {"steps": len(idx), "same": same / len(idx) if idx else None,
                    "within_1": near / len(idx) if idx else None}
        row["agreement"] = {
            "full_localised": agree(lambda q: fm[q]["accepted"]),
            "both_answer": agree(lambda q: fm[q]["library"] >= 0 and rm[q]["library"] >= 0),
            "both_localised": agree(lambda q: fm[q]["accepted"] and rm[q]["accepted"]),
        }
        row["wrong_localised"] = {
            "full": sum(1 for m in fm if m["accepted"] and not m["correct"]),
            "route": sum(1 for m in rm if m["accepted"] and not m["correct"])}
        row["route_counts"] = route["route"]
        if scenario != "lights":
            places = true_places(gt)
            start = route["search"]["start"]
            ev = events(places, n, library_size, 0 if start == "unknown" else start)
            for i, e in enumerate(ev):
                end = ev[i + 1]["query"] if i + 1 < len(ev) else n
                e["until"] = end
                for name, m in [("full", fm), ("route", rm)]:
                    places_to, wrong = recovery(m, e["query"], end)
                    e[name] = {"places": places_to, "wrong_localised": wrong}
            row["events"] = ev
        rows.append(row)

summary = {"threshold": 0.85, "jump_places": JUMP, "pairs": rows}

def f1(x):
    return "-" if x is None else "%.1f" % x

print("## Accuracy (%; difference = route - full, in points)\n")
print("| scenario | seed | pair | queries | top-1 full / route / diff | recall at 100 % precision "
      "full / route / diff | AUC-PR full / route | precision / recall at 0.85 full | "
      "precision / recall at 0.85 route | wrong localised full / route |")
print("|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    print("| %s | %d | %s | %d | %.1f / %.1f / %+.1f | %.1f / %.1f / %+.1f | %.3f / %.3f | "
          "%.1f / %.1f | %.1f / %.1f | %d / %d |" % (
              r["scenario"], r["seed"], r["pair"].split(": ")[-1], r["queries"],
              pct(r["top1"]["full"]), pct(r["top1"]["route"]), pct(r["top1"]["difference"]),
              pct(r["recall_at_100_precision"]["full"]), pct(r["recall_at_100_precision"]["route"]),
              pct(r["recall_at_100_precision"]["difference"]),
              r["auc_pr"]["full"], r["auc_pr"]["route"],
              pct(r["precision"]["full"]), pct(r["recall"]["full"]),
              pct(r["precision"]["route"]), pct(r["recall"]["route"]),
              r["wrong_localised"]["full"], r["wrong_localised"]["route"]))

print("\n## Agreement of the route search with the full search (% same place / within +-1 place)\n")
print("| scenario | seed | pair | (a) full localised: steps, same, +-1 | (b) both answer: steps, "
      "same, +-1 | (c) both localised: steps, same, +-1 | within 1 point: top-1, R@100P |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    a = r["agreement"]
    cells = []
    for k in ["full_localised", "both_answer", "both_localised"]:
        x = a[k]
        cells.append("%d, %s, %s" % (x["steps"], f1(None if x["same"] is None else pct(x["same"])),
                                     f1(None if x["within_1"] is None else pct(x["within_1"]))))
    w = r["within_1_point"]
    print("| %s | %d | %s | %s | %s | %s | %s, %s |" % (
        r["scenario"], r["seed"], r["pair"].split(": ")[-1], cells[0], cells[1], cells[2],
        "yes" if w["top1"] else "no", "yes" if w["recall_at_100_precision"] else "no"))

# The light pairs together: the differences' mean and range, the agreement over all steps.
lights = [r for r in rows if r["scenario"] == "lights"]
if lights:
    pooled = {}
    for k in ["full_localised", "both_answer", "both_localised"]:
        steps = sum(r["agreement"][k]["steps"] for r in lights)
        same = sum(r["agreement"][k]["same"] * r["agreement"][k]["steps"] for r in lights
                   if r["agreement"][k]["steps"])
        near = sum(r["agreement"][k]["within_1"] * r["agreement"][k]["steps"] for r in lights
                   if r["agreement"][k]["steps"])
        pooled[k] = {"steps": steps, "same": same / steps if steps else None,
                     "within_1": near / steps if steps else None}
    diffs = {}
    for k in ["top1", "recall_at_100_precision", "auc_pr", "precision", "recall"]:
        d = [r[k]["difference"] for r in lights]
        diffs[k] = {"mean": sum(d) / len(d), "min": min(d), "max": max(d)}
    within = {k: sum(1 for r in lights if r["within_1_point"][k])
              for k in ["top1", "recall_at_100_precision"]}
    light_summary = {"pairs": len(lights), "agreement": pooled, "difference": diffs,
                     "within_1_point": within}
    print("\n## The %d light pairs together\n" % len(lights))
    for k, label in [("full_localised", "(a) where the full search is localised"),
                     ("both_answer", "(b) where both answer"),
                     ("both_localised", "(c) where both are localised")]:
        x = pooled[k]
        print("- agreement %s: %d steps, same place %s %%, within +-1 place %s %%" % (
            label, x["steps"], f1(pct(x["same"])), f1(pct(x["within_1"]))))
    for k, label in [("top1", "top-1"), ("recall_at_100_precision", "recall at 100 % precision"),
                     ("precision", "precision at 0.85"), ("recall", "recall at 0.85")]:
        print("- %s, route - full: mean %+.1f points (%+.1f .. %+.1f)" % (
            label, pct(diffs[k]["mean"]), pct(diffs[k]["min"]), pct(diffs[k]["max"])))
    print("- AUC-PR, route - full: mean %+.3f (%+.3f .. %+.3f)" % (
        diffs["auc_pr"]["mean"], diffs["auc_pr"]["min"], diffs["auc_pr"]["max"]))
    print("- within 1 point: top-1 on %d of %d pairs, recall at 100 %% precision on %d of %d" % (
        within["top1"], len(lights), within["recall_at_100_precision"], len(lights)))
    summary["lights"] = light_summary

print("\n## What the route search did (counts over the run)\n")
print("| scenario | seed | pair | localised | fixes | scans completed | jumps | carried steps | "
      "steps on probation | withheld below 0.85 |")
print("|---|---|---|---|---|---|---|---|---|---|")
for r in rows:
    c = r["route_counts"]
    print("| %s | %d | %s | %d | %d | %d | %d | %d | %d | %d |" % (
        r["scenario"], r["seed"], r["pair"].split(": ")[-1], c["localised"], c["fixes"],
        c["scans_completed"], c["jumps"], c["carried"], c["probation"], c["withheld"]))

print("\n## Relocalisation: places from each discontinuity to the first correct localised answer "
      "(wrong localised answers before it)\n")
print("| scenario | seed | query | kind | true place from -> to | route search | full search |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    for e in r.get("events", []):
        def cell(x):
            if x["places"] is None:
                return "not before query %d (%d wrong)" % (e["until"], x["wrong_localised"])
            return "%d (%d wrong)" % (x["places"], x["wrong_localised"])
        print("| %s | %d | %d | %s | %d -> %d | %s | %s |" % (
            r["scenario"], r["seed"], e["query"], e["kind"], e["from"], e["to"],
            cell(e["route"]), cell(e["full"])))
json.dump(summary, open(out_file, "w"), indent=1)
print("\nsummary: " + out_file)
EOF
