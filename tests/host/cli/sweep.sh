# seqslam sweep: a 2x2 grid on the corridor pair, resuming (nothing re-run, an interrupted
# last row dropped and re-run), rows equal to seqslam eval's figures, refused outputs and
# pairs files.
source "$(dirname "$0")/lib.sh"
REF="$DATA/corridor/ref"
QRY="$DATA/corridor/query"
GT="$DATA/corridor/ground_truth.csv"
HEADER="library,query,ground_truth,size,preprocess,seq_len,window,exclusion,threshold,max_shift,matcher,metric,queries,top1,recall_at_100_precision,auc_pr,precision_at_recall_0.5,precision_at_recall_0.85,max_recall,accepted,precision,recall,match_ms"

ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
ok "$SEQSLAM" convert images-to-dream "$QRY" query.dream --size 32x16
grid=(--pair "ref.dream,query.dream,$GT" --seq-len 10,20 --window 0,50)

# The rows without match_ms (a time), sorted (rows are appended as they finish, in any order).
rows() { tail -n +2 "$1" | cut -d, -f1-22 | sort; }

ok "$SEQSLAM" sweep "${grid[@]}" --out sweep.csv
out_has "^sweep: 4 combinations x pairs, 0 already in sweep.csv, 4 to run$"
[[ $(head -n 1 sweep.csv) == "$HEADER" ]] || die "sweep.csv header"
[[ $(wc -l <sweep.csv) -eq 5 ]] || die "expected header + 4 rows"
[[ $(rows sweep.csv | cut -d, -f6,7 | tr '\n' ' ') == "10,0 10,50 20,0 20,50 " ]] ||
  die "expected the combinations S 10,20 x W 0,50"
cp sweep.csv full.csv

# Each row equals seqslam eval with the same settings.
for combo in "10 0" "20 50"; do
  read -r s w <<<"$combo"
  ok "$SEQSLAM" eval ref.dream query.dream --ground-truth "$GT" --seq-len "$s" --window "$w" \
    --json "e$s.json" --quiet
  python3 - sweep.csv "e$s.json" "$s" "$w" <<'EOF' || die "sweep row S=$s W=$w differs from eval"
import csv, json, sys
rows = [r for r in csv.DictReader(open(sys.argv[1]))
        if r["seq_len"] == sys.argv[3] and r["window"] == sys.argv[4]]
assert len(rows) == 1, rows
r, s = rows[0], json.load(open(sys.argv[2]))["summary"]
assert int(r["queries"]) == s["queries"] and int(r["accepted"]) == s["accepted"], (r, s)
for k in ["top1", "recall_at_100_precision", "auc_pr", "max_recall", "precision", "recall"]:
    assert abs(float(r[k]) - s[k]) < 1e-5, (k, r[k], s[k])
for k in ["0.5", "0.85"]:
    assert abs(float(r["precision_at_recall_" + k]) - s["precision_at_recall"][k]) < 1e-5, k
EOF
done

# Again: nothing to do, nothing added.
ok "$SEQSLAM" sweep "${grid[@]}" --out sweep.csv
out_has "4 already in sweep.csv, 0 to run"
same full.csv sweep.csv

# The last line cut in half (an interrupted sweep): dropped with a warning, that row re-run.
size=$(stat -c %s full.csv)
last=$(tail -n 1 full.csv | wc -c)
head -c $((size - last / 2)) full.csv >sweep.csv
ok "$SEQSLAM" sweep "${grid[@]}" --out sweep.csv
out_has "3 already in sweep.csv, 1 to run"
err_has "sweep.csv: dropping an incomplete last line"
[[ $(wc -l <sweep.csv) -eq 5 ]] || die "expected header + 4 rows after resuming"
diff <(rows full.csv) <(rows sweep.csv) >&2 || die "the resumed sweep differs"
[[ $(tail -n 1 sweep.csv | cut -d, -f1-22) == $(tail -n 1 full.csv | cut -d, -f1-22) ]] ||
  die "the re-run row should be the one that was cut"

# A row missing (not cut): only that one is run.
sed -i '3d' sweep.csv
ok "$SEQSLAM" sweep "${grid[@]}" --out sweep.csv
out_has "3 already in sweep.csv, 1 to run"
[[ ! -s err.txt ]] || die "nothing to warn about"
diff <(rows full.csv) <(rows sweep.csv) >&2 || die "the completed sweep differs"

# Malformed rows (issue 34: resume kept them and never ran them again): refused with their
# line and what is wrong, the file untouched; nothing is run.
# refused_rows REGEX: malformed.csv is refused naming line 3 with REGEX, and left as it was.
refused_rows() {
  cp malformed.csv malformed.orig
  expect 1 "^seqslam: error: malformed.csv:3: $1; remove the line \(or give another --out\) and run the sweep again$" \
    "$SEQSLAM" sweep "${grid[@]}" --out malformed.csv
  same malformed.orig malformed.csv
}
# bad_row SED REGEX: line 3 of full.csv edited by SED is refused with REGEX.
bad_row() {
  sed "3{$1}" full.csv >malformed.csv
  refused_rows "$2"
}
bad_row 's/,[^,]*$//' "expected 23 comma-separated fields, found 22 .*"
bad_row 's/$/,1/' "expected 23 comma-separated fields, found 24 .*"
bad_row 's/^\(\([^,]*,\)\{10\}\).*/\1diag/' "expected 23 comma-separated fields, found 11 .*"
bad_row 's/^\(\([^,]*,\)\{13\}\)[^,]*/\1nan/' "top1 'nan' is not a number within 0..1"
bad_row 's/^\(\([^,]*,\)\{13\}\)[^,]*/\17/' "top1 '7' is not a number within 0..1"
bad_row 's/^\(\([^,]*,\)\{5\}\)[^,]*/\10/' "seq_len: '0' is not within 1..100 places"
bad_row 's/diagonal/diag\x00nal/' "field 11 'diag\\\\x00nal' holds a control byte: a damaged file"
{
  head -n 2 full.csv
  sed -n 2p full.csv
  tail -n +4 full.csv
} >malformed.csv
refused_rows "the same pair and setting as line 2 \(two sweeps into one file\?\)"
# ... the same checks as tune's, which names the line too.
sed '3{s/^\(\([^,]*,\)\{13\}\)[^,]*/\1nan/}' full.csv >nan.csv
expect 1 "^seqslam: error: nan.csv:3: top1 'nan' is not a number within 0..1 \(re-run the sweep to write the row again\)$" \
  "$SEQSLAM" tune nan.csv

# A pair whose whole matrix passes --max-memory (2 220 places a side, the corridor 20 times:
# 22 MiB): each setting is evaluated in bands instead, with the same rows.
for i in $(seq 20); do ls "$REF"/*.jpg; done >long.txt
ok "$SEQSLAM" convert images-to-dream long.txt long.dream --size 32x16
long=(--pair "long.dream,long.dream,identity:1" --seq-len 10,20)
ok "$SEQSLAM" sweep "${long[@]}" --out long_whole.csv
ok "$SEQSLAM" sweep "${long[@]}" --out long_bands.csv --max-memory 10
[[ $(wc -l <long_bands.csv) -eq 3 ]] || die "long_bands.csv: expected header + 2 rows"
diff <(rows long_whole.csv) <(rows long_bands.csv) >&2 || die "banded sweep rows differ"
expect 1 "the smallest band needs 3 MiB" "$SEQSLAM" sweep "${long[@]}" --out long_1.csv \
  --max-memory 1

# A grid extended by one value runs only the new combinations.
ok "$SEQSLAM" sweep "${grid[@]}" --exclusion 10,5 --out sweep.csv
out_has "8 combinations x pairs, 4 already in sweep.csv, 4 to run"
[[ $(wc -l <sweep.csv) -eq 9 ]] || die "expected header + 8 rows"

# Another file: refused, untouched.
printf 'a,b,c\n1,2,3\n' >other.csv
cp other.csv other.orig
expect 1 "other.csv:1: not a sweep results file of this version \(the header differs\)" \
  "$SEQSLAM" sweep "${grid[@]}" --out other.csv
same other.orig other.csv

# A pairs file (paths relative to it), and one with a bad line.
mkdir pairs
cp ref.dream query.dream pairs/
printf 'library,query,ground_truth,description\nref.dream,query.dream,identity:2,corridor\n' \
  >pairs/pairs.csv
ok "$SEQSLAM" sweep --pairs pairs/pairs.csv --seq-len 10 --out p.csv
[[ $(wc -l <p.csv) -eq 2 ]] || die "p.csv: expected header + 1 row"
[[ $(sed -n 2p p.csv | cut -d, -f1-3) == "pairs/ref.dream,pairs/query.dream,identity:2" ]] ||
  die "p.csv: the pair's paths"
printf 'library,query,ground_truth,description\nref.dream,query.dream,identity:2,ok\n\nonly-one-field\n' \
  >pairs/bad.csv
expect 1 "pairs/bad.csv:4: expected library,query,ground_truth" \
  "$SEQSLAM" sweep --pairs pairs/bad.csv --out bad.csv
[[ ! -e bad.csv ]] || die "bad.csv should not be created"
printf 'lib,qry,gt\n' >pairs/header.csv
expect 1 "pairs/header.csv:1: expected the header" \
  "$SEQSLAM" sweep --pairs pairs/header.csv --out bad.csv
printf 'library,query,ground_truth,description\nref.dream,nosuch.dream,identity:2,x\n' \
  >pairs/missing.csv
expect 1 "nosuch.dream" "$SEQSLAM" sweep --pairs pairs/missing.csv --out bad.csv

# Usage errors: nothing created.
expect 2 "--pair 'a,b': expected LIBRARY,QUERY,GROUND_TRUTH" "$SEQSLAM" sweep --pair a,b --out u.csv
expect 2 "at least one --pair" "$SEQSLAM" sweep --out u.csv
expect 2 "--threshold: '2' is not within 0..1" "$SEQSLAM" sweep "${grid[@]}" --threshold 0.5,2 --out u.csv
expect 2 "--size: '0x3'" "$SEQSLAM" sweep "${grid[@]}" --size 32x16,0x3 --out u.csv
expect 2 "--seq-len: '101' is not within 1..100" "$SEQSLAM" sweep "${grid[@]}" --seq-len 10,101 \
  --out u.csv
expect 2 "" "$SEQSLAM" sweep "${grid[@]}" --seq-len 0 --out u.csv
expect 2 "--out is required" "$SEQSLAM" sweep "${grid[@]}"
[[ ! -e u.csv ]] || die "u.csv should not be created"
echo PASS
