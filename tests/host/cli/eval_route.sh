# seqslam run / eval --search route: the head board's route search on the PC.
#  - equals the firmware: the PC firmware (seqslam-firmware, the head board's app.cpp) teaches
#    the corridor's reference run and repeats a query run with a kidnap (query places 0..70,
#    then 20..110); `seqslam run --search route` on the same two recordings gives the same
#    place, runner-up, confidence, localised flag and route flags at every step as the
#    firmware's results file - with the defaults, and with other route settings given to both
#    (`seqslam config write` and `run` share the option names);
#  - eval --search route: its summary follows from its matches as documented (the recall
#    denominator of the full search; withheld answers ranked last), its JSON carries the
#    settings, the counts and one route_steps entry per query;
#  - --search full (and no --search) output is unchanged;
#  - bad values and combinations are refused with exit status 2 and a message naming the
#    option, writing nothing.
# Usage: eval_route.sh SEQSLAM_FIRMWARE
source "$(dirname "$0")/lib.sh"
FIRMWARE=${1:?seqslam-firmware}
REF="$DATA/corridor/ref"
QRY="$DATA/corridor/query"

# The kidnapped query run, and its ground truth (the corridor's: query i matches i +- 2).
{
  for i in $(seq 0 70) $(seq 20 110); do printf '%s/%07d.jpg\n' "$QRY" "$i"; done
} >kidnapped.txt
{
  echo "query_index,matching_reference_indices"
  q=0
  for i in $(seq 0 70) $(seq 20 110); do
    refs=""
    for r in $((i - 2)) $((i - 1)) $i $((i + 1)) $((i + 2)); do
      ((r >= 0 && r < 111)) && refs="$refs${refs:+ }$r"
    done
    echo "$q,$refs"
    q=$((q + 1))
  done
} >kidnapped.gt.csv
ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
ok "$SEQSLAM" convert images-to-dream kidnapped.txt kidnapped.dream --size 32x16

# The firmware teaches the library once.
ok "$SEQSLAM" disk create teach.img --file config:1K --file replay::ref.dream --file library:64K \
  --file library.img:64K
ok "$SEQSLAM" config write teach.img --modes teach --trigger every-frame
ok "$FIRMWARE" --disk teach.img
ok "$SEQSLAM" disk export teach.img library library.bin
ok "$SEQSLAM" disk export teach.img library.img library_img.bin

# same_as_firmware NAME ROUTE_OPTIONS...: the firmware repeats kidnapped.dream with these
# options (config write), `seqslam run --search route` with the same; every step equal, and
# every route flag set at some step. With NAME defaults the kidnap is also recovered from
# (localised answers after it).
same_as_firmware() {
  local name=$1
  shift
  ok "$SEQSLAM" disk create "$name.img" --file config:1K --file replay::kidnapped.dream \
    --file library::library.bin --file library.img::library_img.bin --file results:64K \
    --file queries:256K
  ok "$SEQSLAM" config write "$name.img" --modes repeat --trigger every-frame "$@"
  ok "$FIRMWARE" --disk "$name.img"
  ok "$SEQSLAM" results "$name.img" --csv "$name.fw.csv"
  ok "$SEQSLAM" run ref.dream kidnapped.dream --search route "$@" --csv "$name.run.csv"
  python3 - "$name.fw.csv" "$name.run.csv" "$name" <<'EOF' || die "$name: seqslam run --search route differs from the firmware"
import csv, sys
fw = list(csv.DictReader(open(sys.argv[1])))
run = list(csv.DictReader(open(sys.argv[2])))
assert len(fw) == len(run) == 162, (len(fw), len(run))
letters = [("tracking", "T"), ("probation", "P"), ("scan", "S"), ("scan_completed", "s"),
           ("jump", "J"), ("carried", "C")]
seen = {k: 0 for k, _ in letters}
localised = 0
for f, r in zip(fw, run):
    q = int(r["query"])
    assert int(f["capture"]) == q, (f, r)
    assert int(f["place"]) == int(r["library"]), (q, f["place"], r["library"])
    assert int(f["runner_up"]) == int(r["runner_up"]), (q, f["runner_up"], r["runner_up"])
    assert f["confidence"] == r["confidence"], (q, f["confidence"], r["confidence"])
    assert int(f["localised"]) == int(r["accepted"]), (q, f["localised"], r["accepted"])
    flags = "".join(l for k, l in letters if r[k] == "1") or "-"
    assert f["route"] == flags, (q, f["route"], flags)
    for k, _ in letters:
        seen[k] += r[k] == "1"
    localised += r["accepted"] == "1"
# Not vacuous: the kidnap took a scan and a jump, answers were on probation, and (with the
# defaults) answers were carried after the jump.
assert all(seen[k] > 0 for k in seen if k != "carried"), seen
assert sys.argv[3] != "defaults" or seen["carried"] > 0, seen
if sys.argv[3] == "defaults":
    assert sum(r["accepted"] == "1" for r in run[71:]) > 0, "no localised answer after the kidnap"
print("same as the firmware:", len(run), "steps,", localised, "localised,", seen)
EOF
}
same_as_firmware defaults
same_as_firmware other --seq-len 20 --route-window 25 --route-slack 3 --route-growth 0.1 \
  --lost-after 12 --scan-places 5 --scan-seq-len 8 --start unknown
# The other settings did change the answers.
! cmp -s defaults.run.csv other.run.csv || die "the route options changed nothing"

# eval --search route: the summary follows from the matches.
ok "$SEQSLAM" eval ref.dream kidnapped.dream --ground-truth kidnapped.gt.csv --search route \
  --json route.json
out_has "^route search: window 25, slack 2, growth 0.05, lost after 30, scan 1024 places a step, scan sequence 10, jump after 14 steps below 0.5, start place 0;" \
  "^133 queries with a full sequence \(the recall denominator\)$" \
  "^route search: [0-9]+ answers localised, [0-9]+ withheld below the threshold"
python3 - route.json defaults.run.csv <<'EOF' || die "route.json: see above"
import csv, json, sys
d = json.load(open(sys.argv[1]))
run = list(csv.DictReader(open(sys.argv[2])))
s, m, steps = d["summary"], d["matches"], d["route_steps"]
assert d["search"] == {"kind": "route", "window": 25, "slack": 2, "growth": 0.05,
                       "lost_after": 30, "scan_places": 1024, "scan_seq_len": 10, "start": 0,
                       "jump_steps": 14, "jump_ratio": 0.5, "match_level": 0.8,
                       "sharpness": 0.85, "tail_steps": 5, "tail_level": 0.9,
                       "query_steps": 512, "library_ram": False}, d["search"]
assert len(m) == len(steps) == len(run) == 162
for x, st, r in zip(m, steps, run):
    assert x["query"] == st["query"] == int(r["query"])
    assert x["library"] == int(r["library"]) and x["accepted"] == (r["accepted"] == "1")
    assert x["accepted"] == st["localised"]
    for k in ["tracking", "probation", "fix", "scan", "scan_completed", "jump", "carried"]:
        assert st[k] == (r[k] == "1"), (x["query"], k)
# The recall denominator: every query with a full sequence (S = 30), as the full search's.
den = sum(1 for x in m if x["library"] >= 0 or x["query"] >= 29)
assert s["queries"] == den == 133, (s["queries"], den)
# Ranking: by confidence, withheld answers (not localised though below 0.85) last.
rec = [(x["confidence"] + (1 if (not x["accepted"] and x["confidence"] < 0.85) else 0),
        x["query"], x["correct"]) for x in m if x["library"] >= 0]
rec.sort()
tp = 0
r100 = 0.0
for i, (c, q, ok) in enumerate(rec):
    tp += ok
    if tp == i + 1 and (i + 1 == len(rec) or rec[i + 1][0] != c):
        r100 = tp / den
    if tp != i + 1:
        break
assert abs(s["recall_at_100_precision"] - r100) < 1e-6, (s["recall_at_100_precision"], r100)
assert abs(s["top1"] - sum(x["correct"] for x in m) / den) < 1e-6, s
acc = [x for x in m if x["accepted"]]
assert s["accepted"] == len(acc) == d["route"]["localised"] > 0, s
assert abs(s["recall"] - sum(x["correct"] for x in acc) / den) < 1e-6, s
assert abs(s["precision"] - sum(x["correct"] for x in acc) / len(acc)) < 1e-6, s
assert d["route"]["jumps"] > 0 and d["route"]["scans_completed"] > 0, d["route"]
EOF

# --search full is the default and changes nothing (JSON apart from the timings and the
# host's figures such as peak memory; CSV).
ok "$SEQSLAM" eval ref.dream kidnapped.dream --ground-truth kidnapped.gt.csv --json default.json
cp out.txt default.txt
ok "$SEQSLAM" eval ref.dream kidnapped.dream --ground-truth kidnapped.gt.csv --search full \
  --json full.json
diff <(grep -v '^time: ' default.txt) <(grep -v '^time: ' out.txt) || die "--search full: other text"
diff <(grep -Ev '"(timing_ms|host)"' default.json) <(grep -Ev '"(timing_ms|host)"' full.json) ||
  die "--search full: other JSON"
! grep -q '"route' full.json || die "--search full: route keys in the JSON"
ok "$SEQSLAM" run ref.dream kidnapped.dream --csv default.csv
ok "$SEQSLAM" run ref.dream kidnapped.dream --search full --csv full.csv
cmp default.csv full.csv || die "--search full: other CSV"
[[ $(head -n 1 full.csv) == "query,library,runner_up,confidence,accepted" ]] || die "full CSV header"
# ... and the route search's answers are not the full search's (the comparison means something).
! cmp -s <(cut -d, -f1-5 defaults.run.csv | tail -n +2) <(tail -n +2 full.csv) ||
  die "the route search gave the full search's answers"

# Refused: exit 2, the option named, nothing written.
refused() {
  local regex=$1
  shift
  rm -f bad.json
  expect 2 "$regex" "$SEQSLAM" eval ref.dream kidnapped.dream --ground-truth kidnapped.gt.csv \
    --json bad.json "$@"
  [[ ! -e bad.json ]] || die "'$*' wrote bad.json although refused"
  [[ ! -s out.txt ]] || die "'$*' printed results although refused"
}
refused "--search: fast not in \{full,route\}" --search fast
refused "--search route: the route search runs the diagonal matcher only \(--matcher heuristic given\)" \
  --search route --matcher heuristic
refused "--search route: the route search runs the diagonal matcher only \(--matcher slope given\)" \
  --search route --matcher slope
refused "--search route: the route search uses the core's SAD \(--metric mad; td given\)" \
  --search route --metric td
refused "--search route: the route search uses the plain SAD: --max-shift must be 0" \
  --search route --max-shift 2
refused "--search route: sequence.seq_len above this firmware's kMaxSeqLen \(the diagonal matcher\) \(it is 31, at most 30;" \
  --search route --seq-len 31
refused "--search route: sequence.exclusion above this firmware's kMaxExclusion \(the route search\) \(it is 11, at most 10;" \
  --search route --exclusion 11
refused "--search route: route.window above this firmware's kWindowSlots \(the route search\) \(it is 27, at most 25;" \
  --search route --route-window 27
refused "--search route: --route-window: route.window must be odd" --search route --route-window 32
refused "--search route: route.window must be at least 2 \* sequence.exclusion \+ 3 \(the route search\)" \
  --search route --route-window 21
refused "--lost-after: '0' is not within 1..65535 places" --search route --lost-after 0
refused "--scan-places: '0' is not within 1..65535 places" --search route --scan-places 0
refused "--scan-seq-len: '0' is not within 1..65535 steps" --search route --scan-seq-len 0
refused "--search route: route.scan_seq_len \(at most S\) above this firmware's kMaxScanSeqLen \(the route search\) \(it is 11, at most 10;" \
  --search route --scan-seq-len 11
refused "--lost-after: '70000' is not within 1..65535" --search route --lost-after 70000
refused "--route-growth: '-1' is not within 0..255.996" --search route --route-growth -1
refused "--route-growth: '256' is not within" --search route --route-growth 256
refused "--route-growth: '0.001' is below half the smallest step" --search route --route-growth 0.001
refused "--route-growth: 'x' is not a decimal number" --search route --route-growth x
refused "--start: '-3' is not a library place" --search route --start -3
refused "--start: '1.5' is not a library place" --search route --start 1.5
refused "--start: 'somewhere' is not a library place" --search route --start somewhere
refused "--start 111: not a place of the library \(source indices 0..110\)" --search route --start 111
refused "--start 5: not a place of the library \(source indices 10..110\)" --search route --start 5 \
  --library-range 10:
refused "--lost-after applies to the route search: add --search route" --lost-after 5
refused "--start applies to the route search: add --search route" --search full --start 3
refused "--search route: --report shows the full search's matrices" --search route --report r.html
refused "--search route: --reference compares the full search" --search route --reference
refused "--search route: --cache: the route search computes no difference matrix" --search route \
  --cache cachedir
expect 2 "--search route: the route search runs the diagonal matcher only" \
  "$SEQSLAM" run ref.dream kidnapped.dream --search route --matcher heuristic
[[ ! -s out.txt ]] || die "run printed results although refused"
# Accepted edge values: growth 0, the largest window the board holds, start unknown, a start
# given as a source index with a library range, a scan sequence longer than S (S is used).
ok "$SEQSLAM" eval ref.dream kidnapped.dream --ground-truth kidnapped.gt.csv --search route \
  --route-growth 0 --route-window 25 --start unknown
out_has "growth 0, lost after 30, scan 1024 places a step, scan sequence 10, jump after 14 steps below 0.5, start unknown;"
ok "$SEQSLAM" eval ref.dream kidnapped.dream --ground-truth kidnapped.gt.csv --search route \
  --library-range 10: --start 10 --seq-len 8 --scan-seq-len 20 --json ranged.json
out_has "start place 10;"
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["search"]["start"] == 10, d["search"]' \
  ranged.json || die "ranged.json: start"
echo PASS
