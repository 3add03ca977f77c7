# results --ground-truth: scores known results against a ground truth, exact figures; where
# the threshold comes from; a ground truth of another run; JSON.
source "$(dirname "$0")/lib.sh"

# capture place confidence_raw localised (UQ16.16: 0.1 = 6554 ... 0.95 = 62259); the step is
# the line's index, the capture (= the query index) is step + 3, so scoring by step would give
# other figures. The flags agree with any threshold above 0.5 and at most 0.88.
cat >spec.txt <<'SPEC'
3 -1 65536 0
4 -1 65536 0
5 10 6554 1
6 11 13107 1
7 30 19661 1
8 13 26214 1
9 14 58982 0
10 50 62259 0
11 16 32768 1
12 17 57672 0
SPEC
# Query q matches library places q+4..q+6: correct are captures 5 6 8 9 11 12, wrong 7 and 10.
# Sorted by confidence: 0.1 C, 0.2 C, 0.3 W, 0.4 C, 0.5 C, 0.88 C, 0.9 C, 0.95 W.
ground_truth() { # FIRST LAST
  echo "query_index,matching_reference_indices"
  for q in $(seq "$1" "$2"); do echo "$q,$((q + 4)) $((q + 5)) $((q + 6))"; done
}
ground_truth 0 12 >gt.csv
"$CLI_FIXTURES" results-list results.bin spec.txt
ok "$SEQSLAM" disk create disk.img --file config:1K --file results::results.bin
ok "$SEQSLAM" config write disk.img # threshold 0.85

# 8 of 10 results have a match candidate; top-1 6/8; below 0.85: 5 accepted, 4 correct;
# 100 % precision up to 2/8; AUC by the trapezoid rule over the 8 points = 0.64315...
ok "$SEQSLAM" results disk.img --ground-truth gt.csv --json scores.json
cat >expected.txt <<'OUT'
disk.img:results: 10 results (5 localised), 0 damaged records; the log ends cleanly
ground truth gt.csv: queries 0..12, 13 with a correct reference
threshold 0.85: the run configuration disk.img:config
8 queries with a full sequence (results with a match candidate; 2 without)
best match correct (top-1, no threshold): 75.0 %
at threshold 0.85: 5 accepted, precision 80.0 %, recall 50.0 %
recall at 100 % precision: 25.0 %; area under the PR curve: 0.643
JSON written to scores.json
OUT
same expected.txt out.txt
[[ ! -s err.txt ]] || die "unexpected stderr: $(cat err.txt)"
cat >expected.json <<'JSON'
{
  "queries": 8,
  "top1": 0.75,
  "threshold": 0.85,
  "accepted": 5,
  "precision": 0.8,
  "recall": 0.5,
  "recall_at_100_precision": 0.25,
  "auc_pr": 0.6431547619047618
}
JSON
same expected.json scores.json

# --json -: the JSON alone on standard output.
ok "$SEQSLAM" results disk.img --ground-truth gt.csv --json -
same expected.json out.txt

# --threshold wins over the configuration. 0.95 is raw 62259, the confidence of capture 10:
# accepted only below it, as the firmware decides: 7 accepted, 6 correct.
ok "$SEQSLAM" results disk.img --ground-truth gt.csv --threshold 0.95
out_has "^threshold 0.95: given with --threshold$" \
  "^at threshold 0.95: 7 accepted, precision 85.7 %, recall 75.0 %$"
[[ ! -s err.txt ]] || die "an explicit threshold is not checked against the flags"

# The configuration's threshold; one that agrees with the flags draws no warning.
ok "$SEQSLAM" config write disk.img --threshold 0.6
ok "$SEQSLAM" results disk.img --ground-truth gt.csv
out_has "^threshold 0.6: the run configuration disk.img:config$" \
  "^at threshold 0.6: 5 accepted, precision 80.0 %, recall 50.0 %$"
[[ ! -s err.txt ]] || die "unexpected stderr: $(cat err.txt)"
# A configuration rewritten after the run: the figures use it, with a warning.
ok "$SEQSLAM" config write disk.img --threshold 0.95
ok "$SEQSLAM" results disk.img --ground-truth gt.csv
out_has "^at threshold 0.95: 7 accepted, precision 85.7 %, recall 75.0 %$"
err_has "^seqslam: warning: 2 of 10 results disagree on 'localised' with threshold 0.95 \(the run configuration disk.img:config\): the firmware ran with another threshold \(configuration changed after the run\?\); the flags fit a threshold above 0.5 and at most 0.88; give --threshold$"

# No config file: the firmware's default. A standalone file: the default.
ok "$SEQSLAM" disk create nocfg.img --file results::results.bin
ok "$SEQSLAM" results nocfg.img --ground-truth gt.csv
out_has "^threshold 0.85: the firmware's default: nocfg.img has no volume file 'config'$" \
  "^at threshold 0.85: 5 accepted, precision 80.0 %, recall 50.0 %$"
ok "$SEQSLAM" results results.bin --ground-truth gt.csv
out_has "^results.bin: 10 results" \
  "^threshold 0.85: the default: a standalone results file does not record the threshold"

# A ground truth for fewer places: the later captures have no correct reference.
# Correct: 5 6 8 of 8; below 0.85 (5, 6, 7, 8, 11): 3 correct.
ground_truth 0 8 >short.csv
ok "$SEQSLAM" results disk.img --ground-truth short.csv --threshold 0.85
out_has "^ground truth short.csv: queries 0..8, 9 with a correct reference$" \
  "^best match correct \(top-1, no threshold\): 37.5 %$" \
  "^at threshold 0.85: 5 accepted, precision 60.0 %, recall 37.5 %$" \
  "^recall at 100 % precision: 25.0 %;"
# ... but one for places the run never reached belongs to another run.
ground_truth 0 13 >long.csv
expect 1 "^seqslam: error: long.csv: the ground truth has queries up to 13, but the results in disk.img:results end at capture 12: the ground truth of another run\?" \
  "$SEQSLAM" results disk.img --ground-truth long.csv
[[ ! -s out.txt ]] || die "no summary for a ground truth of another run"

# The CSV too, to a file: the same CSV as without scoring.
ok "$SEQSLAM" results disk.img --csv plain.csv
ok "$SEQSLAM" results disk.img --ground-truth gt.csv --csv scored.csv --threshold 0.85
same plain.csv scored.csv
out_has "^CSV written to scored.csv$" "^at threshold 0.85: 5 accepted"

# A damaged record in the middle (step 2, capture 5, correct): scored without it, status 1.
cp results.bin mid.bin
flip_byte mid.bin $((1536 + 76 * 2 + 40))
expect 1 "mid.bin: 1 damaged record\(s\) in the middle of the log were skipped" \
  "$SEQSLAM" results mid.bin --ground-truth gt.csv
out_has "^mid.bin: 9 results \(4 localised\), 1 damaged records" \
  "^7 queries with a full sequence \(results with a match candidate; 2 without\)$" \
  "^best match correct \(top-1, no threshold\): 71.4 %$" \
  "^at threshold 0.85: 4 accepted, precision 75.0 %, recall 42.9 %$"
echo PASS
