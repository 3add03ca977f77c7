# seqslam run / eval on the corridor pair: the printed summary, the JSON document (checked with
# python3's json module), one CSV row per query, ranges, and the same results from a dream
# recording, an index file and the image directory.
source "$(dirname "$0")/lib.sh"
REF="$DATA/corridor/ref"
QRY="$DATA/corridor/query"
GT="$DATA/corridor/ground_truth.csv"

# eval: the corridor is localised perfectly (Milford 2013; README).
ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" --json eval.json
out_has "^library .*: 111 images; query .*: 111 images; 12x10 he-pn, S=30, W=50, R=10" \
  "^82 queries with a full sequence \(the recall denominator\)$" \
  "^best match correct \(top-1, no threshold\): 100\.0 %$" \
  "^recall at 100 % precision: 100\.0 %; area under the PR curve: 1\.000$"
python3 - eval.json <<'EOF' || die "eval.json: see above"
import json, sys
d = json.load(open(sys.argv[1]))
s = d["summary"]
for k in ["queries", "recall_at_100_precision", "auc_pr", "precision_at_recall", "max_recall", "top1"]:
    assert k in s, "summary lacks " + k
assert set(s["precision_at_recall"]) == {"0.5", "0.85"}, s["precision_at_recall"]
assert s["queries"] == 82 and s["top1"] == 1 and s["recall_at_100_precision"] == 1, s
m = d["matches"]
assert len(m) == 111, len(m)
for i, x in enumerate(m):
    for k in ["query", "library", "confidence", "accepted", "correct"]:
        assert k in x, "match %d lacks %s" % (i, k)
    assert x["query"] == i, x
    assert (x["library"] >= 0) == (i >= 29), x  # S = 30
    assert 0 <= x["confidence"] <= 1, x
    assert not x["accepted"] or x["library"] >= 0, x
# The summary is computed from these matches (recall denominator: every query with a full
# sequence, i.e. a candidate).
den = sum(1 for x in m if x["library"] >= 0)
assert s["queries"] == den, (s["queries"], den)
assert abs(s["top1"] - sum(1 for x in m if x["correct"]) / den) < 1e-6
acc = [x for x in m if x["accepted"]]
assert s["accepted"] == len(acc) > 0, s
assert abs(s["recall"] - sum(1 for x in acc if x["correct"]) / den) < 1e-6, s
assert d["library"]["images"] == 111 and d["query"]["kind"] == "directory", d["query"]
EOF

# --quiet prints nothing; --json - prints only the document.
ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth identity:2 --quiet
[[ ! -s out.txt ]] || die "--quiet printed something"
ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth identity:2 --quiet --json -
python3 -c 'import json,sys; json.load(open(sys.argv[1]))' out.txt || die "--json - is not JSON"

# run: one CSV row per query (default stdout), no ground-truth columns.
ok "$SEQSLAM" run "$REF" "$QRY"
cp out.txt run.csv
[[ $(head -n 1 run.csv) == "query,library,runner_up,confidence,accepted" ]] || die "run.csv header"
[[ $(wc -l <run.csv) -eq 112 ]] || die "run.csv: expected 111 rows"
[[ $(sed -n 2p run.csv) == "0,-1,-1,1.000000,0" ]] || die "run.csv: query 0 has no sequence yet"
[[ $(sed -n 31p run.csv | cut -d, -f1) == 29 ]] || die "run.csv: row order"
[[ $(sed -n 31p run.csv | cut -d, -f2) -ge 0 ]] || die "run.csv: query 29 has a full sequence"
# The same matches as eval's JSON.
python3 - run.csv eval.json <<'EOF' || die "run.csv and eval.json disagree"
import csv, json, sys
rows = list(csv.DictReader(open(sys.argv[1])))
m = json.load(open(sys.argv[2]))["matches"]
assert len(rows) == len(m) == 111
for r, x in zip(rows, m):
    assert int(r["query"]) == x["query"] and int(r["library"]) == x["library"], (r, x)
    assert abs(float(r["confidence"]) - x["confidence"]) < 2e-6, (r, x)
    assert (r["accepted"] == "1") == x["accepted"], (r, x)
EOF
ok "$SEQSLAM" run "$REF" "$QRY" --csv file.csv --threads 1
[[ ! -s out.txt ]] || die "run --csv FILE printed to stdout"
same run.csv file.csv
ok "$SEQSLAM" run "$REF" "$QRY" --json run.json --threads 2
[[ ! -s out.txt ]] || die "run --json FILE printed to stdout"
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["summary"] is None and len(d["matches"]) == 111' \
  run.json || die "run.json"

# Ranges: source indices in the output, as many rows as the range.
ok "$SEQSLAM" run "$REF" "$QRY" --query-range 10:60 --seq-len 10
[[ $(wc -l <out.txt) -eq 51 ]] || die "--query-range 10:60: expected 50 rows"
[[ $(sed -n 2p out.txt | cut -d, -f1) == 10 && $(tail -n 1 out.txt | cut -d, -f1) == 59 ]] ||
  die "--query-range 10:60: queries 10..59"
ok "$SEQSLAM" run "$REF" "$QRY" --query-range 100: --library-range :40 --seq-len 5
[[ $(wc -l <out.txt) -eq 12 ]] || die "--query-range 100:: expected 11 rows"
awk -F, 'NR > 1 && ($2 >= 40 || $3 >= 40) { exit 1 }' out.txt || die "library beyond 40 reported"
ok "$SEQSLAM" run "$REF" "$QRY" --library-range 50:90 --seq-len 5
awk -F, 'NR > 1 && $2 != -1 && ($2 < 50 || $2 >= 90) { exit 1 }' out.txt ||
  die "--library-range 50:90: library indices must be source indices 50..89"
ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" --query-range 40:100 --library-range 30: \
  --json ranged.json
out_has "^31 queries with a full sequence \(the recall denominator\)$"
python3 - ranged.json <<'EOF' || die "ranged.json"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["query"]["first"] == 40 and d["query"]["images"] == 60, d["query"]
assert d["library"]["first"] == 30 and d["library"]["images"] == 81, d["library"]
assert [x["query"] for x in d["matches"]] == list(range(40, 100))
assert d["summary"]["queries"] == 31 and d["summary"]["top1"] == 1, d["summary"]
EOF

# A dream recording and an index file give the same results as the image directory.
ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 12x10
ok "$SEQSLAM" convert images-to-dream "$QRY" query.dream --size 12x10
ok "$SEQSLAM" run ref.dream query.dream
same run.csv out.txt
ls "$QRY"/*.jpg >query.txt
ok "$SEQSLAM" run "$REF" query.txt
same run.csv out.txt
ok "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --json dream.json
python3 - eval.json dream.json <<'EOF' || die "dream.json differs from eval.json"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
assert a["matches"] == b["matches"]
assert a["summary"] == b["summary"]
assert b["library"]["kind"] == "dream", b["library"]
EOF
ok "$SEQSLAM" run ref.dream query.dream --query-range 10:60 --seq-len 10
cp out.txt dream_range.csv
ok "$SEQSLAM" run "$REF" "$QRY" --query-range 10:60 --seq-len 10
same dream_range.csv out.txt

# Other settings change the results (the options reach the engine).
ok "$SEQSLAM" run ref.dream query.dream --preprocess pn --seq-len 10 --window 0 --max-shift 2 \
  --exclusion 5 --threshold 0.5
cmp -s run.csv out.txt && die "other settings gave the same results"
awk -F, 'NR > 1 && $5 == 1 && $4 >= 0.5 { exit 1 }' out.txt || die "accepted at confidence >= 0.5"

# The difference-matrix cache: the second run says so and changes nothing.
ok "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --cache cache --json c1.json
[[ $(ls cache | wc -l) -eq 1 ]] || die "expected one cache file"
ok "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --cache cache --json c2.json
out_has "differences [0-9]+ ms \(cached\)"
python3 - eval.json c1.json c2.json <<'EOF' || die "cached results differ"
import json, sys
a, b, c = (json.load(open(f)) for f in sys.argv[1:4])
assert not b["timing_ms"]["matrix_from_cache"] and c["timing_ms"]["matrix_from_cache"]
assert a["matches"] == b["matches"] == c["matches"]
EOF
# Bands of query rows (--band) give the same results as the whole matrix; a plan over
# --max-memory is refused with the figure it needs, and --report keeps the whole matrix.
for band in 1 16 111; do
  ok "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --band "$band" --json band.json
  python3 - c1.json band.json "$band" <<'EOF' || die "--band $band: other results"
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
assert a["matches"] == b["matches"] and a["summary"] == b["summary"]
assert b["host"]["band_rows"] == int(sys.argv[3]), b["host"]
assert a["host"]["band_rows"] == 111, a["host"]  # --cache: the whole matrix
EOF
done
# 2 220 images a side (the corridor 20 times): at 32x16 their 2.2 MB of images alone pass 1 MiB.
for i in $(seq 20); do ls "$REF"/*.jpg; done >long.txt
expect 1 "the smallest band needs 3 MiB .*limit is 1 MiB \(--max-memory\)" \
  "$SEQSLAM" eval long.txt long.txt --ground-truth identity:1 --size 32x16 --max-memory 1
expect 1 "needs 22 MiB \(images 3, difference rows 19 for a band of 2220 query rows.*limit is 4" \
  "$SEQSLAM" eval long.txt long.txt --ground-truth identity:1 --size 32x16 --max-memory 4 \
  --band 5000
expect 1 "--band must be 0" \
  "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --band 16 --report r.html
[[ ! -e r.html ]] || die "a refused --report wrote its file"
expect 2 "" "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --max-memory 0
expect 2 "" "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --band -1

# The other matchers and the tangent-distance metric run through the same command.
for opt in "--matcher slope" "--matcher heuristic" "--metric td"; do
  # shellcheck disable=SC2086
  ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" $opt --json other.json
  out_has "^best match correct \(top-1, no threshold\): [0-9.]+ %$"
  python3 - other.json "$opt" <<'EOF' || die "$opt: JSON"
import json, sys
d = json.load(open(sys.argv[1]))
key, value = sys.argv[2].split()
key = key.lstrip("-")
assert d["config"][key] == value, (d["config"], sys.argv[2])
assert len(d["matches"]) == 111 and 0 <= d["summary"]["top1"] <= 1, d["summary"]
EOF
done
"$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" --matcher slope --vmin 1.2 --vmax 0.8 \
  > out.txt 2>&1 && die "vmin > vmax accepted"
grep -q "slope: vmin must be above 0 and at most vmax" out.txt ||
  die "no message for vmin > vmax: $(cat out.txt)"
"$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" --metric l2 > out.txt 2>&1 &&
  die "--metric l2 accepted"

# --reference ranks the same answers under three offsets of the confidence
# (docs/normalisation.md). Corridor, 32x16 HE, S = 10: the figures of test_oracle's own batch
# rule (its settings).
ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" --size 32x16 --preprocess he --seq-len 10 \
  --reference --json ref.json
out_has "^reference, online offset \(the core's rule\): top-1 62\.7 %, recall at 100 % precision 25\.5 %" \
  "^reference, batch global minimum \(not online\): top-1 62\.7 %, recall at 100 % precision 13\.7 %" \
  "^reference, fixed offset \(costs as stored\): top-1 62\.7 %, recall at 100 % precision 21\.6 %"
python3 - ref.json <<'EOF' || die "ref.json: see above"
import json, sys
r = json.load(open(sys.argv[1]))["reference"]
assert r["same_place"] == r["compared"] == 102, r
for rule in ("batch", "fixed_offset"):
    assert r[rule]["same_place"] == 102 and r[rule]["top1"] == r["top1"], r[rule]
assert abs(r["batch"]["recall_at_100_precision"] - 14 / 102) < 1e-6, r["batch"]
EOF
echo PASS
