# seqslam run / eval / sweep answer --help with status 0, their usage line and options, and
# print nothing unprintable.
source "$(dirname "$0")/lib.sh"

for sub in run eval sweep; do
  ok "$SEQSLAM" $sub --help
  out_has "^Usage: seqslam $sub " "--size" "--preprocess" "--seq-len" "--window" "--exclusion" \
    "--threshold" "--max-shift" "--matcher" "--threads" "--cache"
done
run "$SEQSLAM" run --help
out_has "library TEXT REQUIRED" "query TEXT REQUIRED" "--csv" "--json" "--library-range" \
  "--query-range"
run "$SEQSLAM" eval --help
out_has "--ground-truth" "identity:TOL" "poses:METRES" "--json" "--report" "--library-range"
run "$SEQSLAM" sweep --help
out_has "--pair " "--pairs" "--out" "REQUIRED"

# Every default shown is printable text (a uint8_t option with capture_default_str() once
# printed --max-shift's default 0 as the character '\0').
for sub in run eval sweep; do
  run "$SEQSLAM" $sub --help
  if [[ $(tr -cd '\000' <out.txt | wc -c) -ne 0 ]]; then
    grep -a -- "--max-shift" out.txt | od -c | head -2 >&2
    die "'seqslam $sub --help' prints a NUL byte"
  fi
done
echo PASS
