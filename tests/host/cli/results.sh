# results: table and CSV, exact values, damaged records.
source "$(dirname "$0")/lib.sh"

# 12 results; each record is 20 bytes of framing + 56 of payload, from byte 512.
"$CLI_FIXTURES" results results.bin 12 expected.csv
record() { echo $((1536 + 76 * $1)); }  # after the header and the commit slots

ok "$SEQSLAM" disk create disk.img --file config:1K --file results::results.bin
ok "$SEQSLAM" results disk.img --csv got.csv
same expected.csv got.csv
out_has "^got.csv: 12 results \([0-9]+ localised\), 0 damaged records; the log ends cleanly$"
ok "$SEQSLAM" results disk.img --csv -
same expected.csv out.txt
ok "$SEQSLAM" results disk.img:results --csv -
same expected.csv out.txt
ok "$SEQSLAM" results results.bin --csv -
same expected.csv out.txt
[[ ! -s err.txt ]] || die "unexpected stderr: $(cat err.txt)"

ok "$SEQSLAM" results disk.img
out_has "^ +step +capture +timestamp_us +x_m +y_m" "^12 results \(" "the log ends cleanly$"
[[ $(wc -l <out.txt) -eq 14 ]] || die "table: header, 12 rows, summary"
# Results without route-search flags (route byte 0: other searches, older firmware) print as
# before: no route column, no route summary.
out_has " confidence localised$"
! grep -q "route" out.txt || die "no route column or summary without route flags"

# Route-search flags: a route column (letters T P S s J C, ? unknown bits, - none) in the
# CSV and the table, and a summary line counting them.
"$CLI_FIXTURES" results-route route.bin route_expected.csv
ok "$SEQSLAM" results route.bin --csv -
same route_expected.csv out.txt
ok "$SEQSLAM" results route.bin --csv route.csv
same route_expected.csv route.csv
route_line="route search: scans completed 4, jumps 3, carried answers 4; steps with the scan running 6, on probation 4, tracking 8"
out_has "^route.csv: 16 results \(1 localised\), 0 damaged records; the log ends cleanly$" \
  "^route.csv: $route_line$"
ok "$SEQSLAM" results route.bin
out_has " confidence localised +route$" \
  "^ +0 +0 +0 .* 0.5000 no +-$" \
  "^ +12 +12 +120000 .* no +TPSsJC$" \
  "^ +14 +14 .* no +TC\?$" \
  "^ +15 +15 .* yes +T$" \
  "^16 results \(1 localised\), 0 damaged records; the log ends cleanly$" \
  "^$route_line$"
[[ $(wc -l <out.txt) -eq 19 ]] || die "route table: header, 16 rows, summary, route summary"

# A damaged record in the middle: the rest is printed, a warning, status 1.
cp results.bin mid.bin
flip_byte mid.bin $(($(record 3) + 40))
expect 1 "mid.bin: 1 damaged record\(s\) in the middle of the log were skipped" \
  "$SEQSLAM" results mid.bin --csv mid.csv
grep -v '^3,' expected.csv >expected_mid.csv
same expected_mid.csv mid.csv

# The last record damaged after it was committed (not a power cut, which leaves it
# uncommitted): the records before it are printed, the loss is reported, status 1.
cp results.bin tail.bin
flip_byte tail.bin $(($(record 11) + 40))
expect 1 "tail.bin: .*the log ends before its committed end" \
  "$SEQSLAM" results tail.bin --csv tail.csv
head -n 12 expected.csv >expected_tail.csv
same expected_tail.csv tail.csv

# No results written yet.
ok "$SEQSLAM" disk create empty.img --file results:4K
expect 1 "empty.img:results: empty: block 0 is all zeros \(no results written yet\)" \
  "$SEQSLAM" results empty.img
# Not a results file.
expect 1 "disk.img:config: empty" "$SEQSLAM" results disk.img:config
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 8x4
expect 1 "ref.dream: not a readable results: not a log of the expected kind" \
  "$SEQSLAM" results ref.dream
echo PASS
