# seqslam tune: leave-one-pair-out choice from sweep results. The choices are checked against
# an independent selection in python from the same rows; bad files and usage are refused.
source "$(dirname "$0")/lib.sh"
REF="$DATA/corridor/ref"
QRY="$DATA/corridor/query"
GT="$DATA/corridor/ground_truth.csv"

ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
ok "$SEQSLAM" convert images-to-dream "$QRY" query.dream --size 32x16
# Three pairs: the corridor both ways, and the query against itself.
ok "$SEQSLAM" sweep --pair "ref.dream,query.dream,$GT" --pair "query.dream,ref.dream,identity:3" \
  --pair "query.dream,query.dream,identity:0" --preprocess he,pn --seq-len 10,30 --window 0,50 \
  --out grid.csv --quiet
# Without --default, the default is the settings table's (the run configuration's), which this
# 32x16 grid does not hold; the rules below are checked against 32x16 he.
ok "$SEQSLAM" tune grid.csv
out_has "; default 12x10,he-pn,30,50,10,0.85,0,diagonal,mad\.$" \
  "^The default setting was not swept: no comparison\.$"
DEF="32x16,he,30,50,10,0.85,0,diagonal,mad"
ok "$SEQSLAM" tune grid.csv --default "$DEF" --out tune.md
[[ ! -s out.txt ]] || die "tune --out FILE printed to stdout"
ok "$SEQSLAM" tune grid.csv --default "$DEF" --objective mean --measure recall-at-100 \
  --no-smoothing --no-dataset-balance --out tune-recall.md
# Both rules chosen again in python from the same rows: issue 33's (the worst gain over the
# default of the AUC smoothed over the S and W neighbours, ties to the mean AUC, the mean recall
# at 100 % precision, the mean top-1; one dataset here) and the rule before it (the mean recall
# at 100 % precision, ties to the mean AUC and top-1).
python3 - grid.csv tune.md tune-recall.md <<'EOF' || die "tune's choices differ from the independent selection"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
pair = lambda r: ",".join((r["library"], r["query"], r["ground_truth"]))
setting = lambda r: ",".join(r[k] for k in ["size", "preprocess", "seq_len", "window", "exclusion",
                                            "threshold", "max_shift", "matcher", "metric"])
order = list(dict.fromkeys(pair(r) for r in rows))
pairs = sorted(order)  # tune sums in the order of the pair's text
table = {}
for r in rows:
    table.setdefault(setting(r), {})[pair(r)] = tuple(
        float(r[k]) for k in ["recall_at_100_precision", "auc_pr", "top1"])
default = "32x16,he,30,50,10,0.85,0,diagonal,mad"
def neighbours(s):
    f = s.split(",")
    out = []
    for c in (2, 3):
        same = [t for t in table if all(k == c or a == b for k, (a, b) in
                                        enumerate(zip(t.split(","), f)))]
        values = sorted({int(t.split(",")[c]) for t in same})
        i = values.index(int(f[c]))
        for j in (i - 1, i + 1):
            if 0 <= j < len(values):
                out.append(",".join(f[:c] + [str(values[j])] + f[c + 1:]))
    return out
smooth = {s: {p: min([table[s][p][1]] + [table[n][p][1] for n in neighbours(s)]) for p in pairs}
          for s in table}
def mean(values):
    return sum(values) / len(values)
def new_rule(skip):
    def key(s):
        tr = [p for p in pairs if p != skip]
        return (min(smooth[s][p] - table[default][p][1] for p in tr),
                mean([smooth[s][p] for p in tr]), mean([table[s][p][0] for p in tr]),
                mean([table[s][p][2] for p in tr]))
    return max(sorted(table), key=lambda s: (key(s), [-ord(c) for c in s]))
def old_rule(skip):
    def key(s):
        v = [table[s][p] for p in pairs if p != skip]
        return tuple(mean([x[i] for x in v]) for i in range(3))
    return max(sorted(table), key=lambda s: (key(s), [-ord(c) for c in s]))
for md_path, choose, column in ((sys.argv[2], new_rule, 1), (sys.argv[3], old_rule, 0)):
    md = open(md_path).read()
    lines = [l for l in md.splitlines() if l.startswith("| ") and "->" in l]
    assert len(lines) == len(order) == 3, lines
    for p, line in zip(order, lines):
        cells = [c.strip() for c in line.strip("|").split("|")]
        chosen = choose(p)
        assert cells[2] == chosen, (md_path, cells, chosen)
        assert cells[3] == "%.1f" % (100 * table[chosen][p][column]), (cells, chosen)
        assert cells[5] == "%.1f" % (100 * table[default][p][column]), cells
    assert "distinct setting(s) chosen over 3 folds" in md, md
    assert "the best over all pairs, %s," % choose(None) in md, md
EOF
grep -q "^| ref -> query | \. | " tune.md || die "pair label: $(cat tune.md)"

# To standard output by default; --default another setting changes the comparison only.
ok "$SEQSLAM" tune grid.csv --default "32x16,pn,10,0,10,0.85,0,diagonal,mad"
out_has "^\| query -> ref \| " "Worst held-out difference against the default \(AUC, points\): "
ok "$SEQSLAM" tune grid.csv --default "32x16,he,20,50,10,0.85,0,diagonal,mad"
out_has "The default setting was not swept: no comparison."
# A --default sweep could not have run is refused (issue 34: it exited 0, "not swept").
expect 2 "^seqslam: error: --default: '32x16,he,30' is not 9 comma-separated values size,preprocess" \
  "$SEQSLAM" tune grid.csv --default "32x16,he,30"
expect 2 "^seqslam: error: --default: threshold: 'nan' is not a decimal number \(0..1\)$" \
  "$SEQSLAM" tune grid.csv --default "32x16,he,30,50,10,nan,0,diagonal,mad"
expect 2 "^seqslam: error: --default: seq_len: '0' is not within 1..100 places$" \
  "$SEQSLAM" tune grid.csv --default "32x16,he,0,50,10,0.85,0,diagonal,mad"
expect 2 "^seqslam: error: --default: the setting is invalid: " \
  "$SEQSLAM" tune grid.csv --default "32x16,he,30,1,10,0.85,0,diagonal,mad"
expect 2 "^seqslam: error: --default: size: '64x16' has 1024 pixels; the FPGA pixel buffer holds at most 512 \(W \* H <= 512\)$" \
  "$SEQSLAM" tune grid.csv --default "64x16,he,30,50,10,0.85,0,diagonal,mad"

# Bad input: named with its line; usage: status 2; nothing written.
head -n 1 grid.csv > one.csv
grep "ref.dream,query.dream" grid.csv >> one.csv
expect 1 "at least two pairs" "$SEQSLAM" tune one.csv
head -n 3 grid.csv > cut.csv
head -c 40 <(sed -n 4p grid.csv) >> cut.csv
expect 1 "cut.csv:4: expected 23 comma-separated fields" "$SEQSLAM" tune cut.csv
echo "library,query" > other.csv
expect 1 "other.csv:1: not a sweep results file" "$SEQSLAM" tune other.csv
expect 1 "nosuch.csv: no such file" "$SEQSLAM" tune nosuch.csv
# Regular files only: /dev/zero has no line end (it grew to gigabytes and never ended).
expect 1 "^seqslam: error: /dev/zero: is not a regular file" timeout 60 "$SEQSLAM" tune /dev/zero
mkfifo fifo.csv
expect 1 "^seqslam: error: fifo.csv: is not a regular file" timeout 60 "$SEQSLAM" tune fifo.csv
expect 2 "grid.csv: is also an input" "$SEQSLAM" tune grid.csv --out grid.csv
expect 2 "" "$SEQSLAM" tune
[[ $(head -n 1 grid.csv) == library,query,* ]] || die "grid.csv was touched"
echo PASS
