# seqslam report-slam on the output of seqslam slam for seqslam-sim's explore-short run: the
# page holds the three maps, the trajectories, the closures and the figures of the run's
# JSON; bad input (a missing directory, a malformed CSV line, a broken map, bad JSON) exits 1
# naming the file and line (the JSON: the line and column, or the key), a missing --out
# exits 2.
# $1: the seqslam-sim program.
source "$(dirname "$0")/lib.sh"
SIM=${1:?seqslam-sim path}
[[ -x $SIM ]] || die "$SIM not built (cmake --build ... --target seqslam-sim)"

ok "$SIM" generate --scenario explore-short --seed 1 --out sim
ok "$SEQSLAM" slam sim/explore_short_noon-lamps.dream --out out --json out/slam.json --quiet
ok "$SEQSLAM" report-slam out --true-map sim/lab_map.yaml --out report.html
out_has "^report: report.html"
python3 - report.html out/slam.json out/trajectory.csv out/closures.csv <<'PY' || die "page incomplete"
import csv, json, re, sys
html = open(sys.argv[1]).read()
d = json.load(open(sys.argv[2]))
rows = list(csv.DictReader(open(sys.argv[3])))
closures = list(csv.DictReader(open(sys.argv[4])))
for i in ("map-true", "map-corrected", "map-odometry", "slam-figures"):
    assert html.count('id="%s"' % i) == 1, i
assert html.count('src="data:image/png;base64,') == 3
assert "<link" not in html and "<script" not in html
assert html.count('class="traj-true"') == 3
assert html.count('class="traj-corrected"') == 2 and html.count('class="traj-odometry"') == 2
# Every closure drawn twice (true and corrected poses).
assert html.count("<title>closure ") == 2 * len(closures) == 2 * d["closures"], d["closures"]
def fig(key):
    m = re.search(r'<tr data-key="%s"><td>[^<]*</td><td class="v">([^<]*)</td>' % re.escape(key), html)
    assert m, key
    return m.group(1)
assert fig("rmse_corrected_m") == "%.3f" % d["rmse_corrected_m"]
assert fig("rmse_dead_reckoning_m") == "%.3f" % d["rmse_dead_reckoning_m"]
assert fig("ratio") == "%.2f" % (d["rmse_corrected_m"] / d["rmse_dead_reckoning_m"])
assert fig("closures") == str(d["closures"])
assert fig("false_closures") == str(d["false_closures"])
assert fig("rejected_position") == str(d["rejected_position"])
assert fig("rejected_heading") == str(d["rejected_heading"])
assert fig("map_accuracy_corrected") == "%.3f" % d["map_accuracy_corrected"]
assert fig("map_accuracy_dead_reckoning") == "%.3f" % d["map_accuracy_dead_reckoning"]
# Obstacles near the true path: in the table and under the two built maps.
for m in ("corrected", "dead_reckoning"):
    for k in ("occupied_precision", "occupied_recall", "occupied_precision_within_1_cell",
              "occupied_recall_within_1_cell", "balanced_accuracy"):
        assert fig("near_path.%s.%s" % (m, k)) == "%.3f" % d["near_path"][m][k], (m, k)
captions = re.findall(r'<span class="near-path">([^<]*)</span>', html)
assert len(captions) == 2, captions
for c, m in zip(captions, ("corrected", "dead_reckoning")):
    assert "occupied precision %.3f, recall %.3f" % (
        d["near_path"][m]["occupied_precision"], d["near_path"][m]["occupied_recall"]) in c, c
# The last corrected pose is on the corrected polyline at (x, -y).
last = rows[-1]
assert "%.3f,%.3f" % (float(last["corrected_x"]), -float(last["corrected_y"])) in html
PY

# Defaults: DIR/slam.json is found without --json; without a true map the page says so.
ok "$SEQSLAM" report-slam out --out plain.html
grep -q "No true map given" plain.html || die "no note about the missing true map"
grep -q "the slam JSON" plain.html || die "DIR/slam.json not used by default"
# Without the JSON the figures near the path are computed from the files, to the same values.
mkdir nojson && cp out/*.csv out/*.pgm out/*.yaml nojson/
ok "$SEQSLAM" report-slam nojson --true-map sim/lab_map.yaml --out nojson.html
python3 - report.html nojson.html <<'PY' || die "near-path figures computed differently"
import re, sys
a, b = (re.findall(r'<span class="near-path">([^<]*)</span>', open(p).read()) for p in sys.argv[1:])
assert len(a) == 2 and a == b, (a, b)
PY
# A figures JSON written before the figures near the path reads; they are computed instead.
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); del d['near_path']; json.dump(d, open(sys.argv[2], 'w'))" out/slam.json nojson/slam.json
ok "$SEQSLAM" report-slam nojson --true-map sim/lab_map.yaml --out old.html
grep -q '<td>near the true path (1.00 m), corrected: occupied precision</td><td class="v">[0-9.]*</td><td>computed from the files' old.html ||
  die "old JSON: near-path figures not computed"

# Bad input.
expect 1 "nothing/trajectory.csv" "$SEQSLAM" report-slam nothing --out x.html
cp -r out bad
sed -i '3s/,[^,]*$//' bad/trajectory.csv
expect 1 "bad/trajectory.csv:3: [0-9]+ fields" "$SEQSLAM" report-slam bad --out x.html
cp out/trajectory.csv bad/trajectory.csv
# A closure naming a place beyond the run (the other columns as the file has them).
tail -n 1 out/closures.csv | awk -F, -v OFS=, '{ $2 = 999999; print }' >> bad/closures.csv
expect 1 "bad/closures.csv:[0-9]+: places must be indices below" \
  "$SEQSLAM" report-slam bad --out x.html
cp out/closures.csv bad/closures.csv
printf 'P5\n3 3\n255\nxy' > bad/map.pgm
expect 1 "bad/map.yaml: image:" "$SEQSLAM" report-slam bad --out x.html
cp out/map.pgm bad/map.pgm
printf '{\n  "places": 1,\n' > bad/slam.json
expect 1 "bad/slam.json: not JSON: parse error at line 3, column 1: .*unexpected end of input" \
  "$SEQSLAM" report-slam bad --out x.html
sed 's/"closures": \([0-9]*\)/"closures": "\1"/' out/slam.json > bad/slam.json
expect 1 "bad/slam.json: 'closures' must be a whole number from 0 to [0-9]+, found a string" \
  "$SEQSLAM" report-slam bad --out x.html
grep -v '"has_map"' out/slam.json > bad/slam.json
expect 1 "bad/slam.json: missing key 'has_map'" "$SEQSLAM" report-slam bad --out x.html
expect 1 "lab.yaml" "$SEQSLAM" report-slam out --true-map lab.yaml --out x.html
[[ ! -e x.html ]] || die "a page was written for bad input"
expect 2 "" "$SEQSLAM" report-slam out

# Under a file size limit with SIGXFSZ untrapped (issue 34: it died with status 153 and left
# its temporary): status 1 naming the page, no temporary, an old page kept.
echo "old page" >limited.html
cp limited.html limited.orig
expect 1 "^seqslam: error: limited.html: write failed: File too large$" \
  bash -c 'ulimit -f 1 && exec "$0" report-slam out --true-map sim/lab_map.yaml --out limited.html' \
  "$SEQSLAM"
same limited.orig limited.html
[[ -z $(find . -maxdepth 1 -name '.*.tmp-*') ]] || die "temporaries left behind"
echo PASS
