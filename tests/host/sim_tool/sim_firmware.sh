#!/usr/bin/env bash
# seqslam-sim end to end: determinism of the files (same seed, any thread count), and the
# firmware replaying a simulated run captures exactly the simulated places and scores
# against the simulated ground truth. Usage: sim_firmware.sh BIN_DIR WORK_DIR
set -euo pipefail
BIN=$1
WORK=$2
rm -rf "$WORK"
mkdir -p "$WORK"
fail() { echo "FAIL: $*" >&2; exit 1; }

"$BIN/seqslam-sim" generate --scenario short --seed 7 --jobs 1 --out "$WORK/a" > /dev/null
"$BIN/seqslam-sim" generate --scenario short --seed 7 --jobs 2 --out "$WORK/b" > /dev/null
"$BIN/seqslam-sim" generate --scenario short --seed 8 --jobs 2 --out "$WORK/c" > /dev/null
files=$(cd "$WORK/a" && ls)
[ "$(echo "$files" | wc -l)" -ge 9 ] || fail "too few files: $files"
for f in $files; do
  cmp -s "$WORK/a/$f" "$WORK/b/$f" || fail "$f differs between --jobs 1 and --jobs 2 (same seed)"
done
cmp -s "$WORK/a/short_noon-lamps.dream" "$WORK/c/short_noon-lamps.dream" &&
  fail "seeds 7 and 8 gave the same recording"
echo "deterministic: $(echo "$files" | wc -l) files identical for seed 7 with 1 and 2 threads"

# Teach on the library run; the firmware must capture at every simulated place.
places=$(awk -F, '$1 == "short_noon-lamps" {print $3}' "$WORK/a/runs.csv")
[ -n "$places" ] && [ "$places" -gt 40 ] || fail "unexpected place count '$places'"
"$BIN/seqslam" disk create "$WORK/teach.img" --file config:4K \
  --file "replay::$WORK/a/short_noon-lamps.dream" --file library:256K --file library.img:256K > /dev/null
"$BIN/seqslam" config write "$WORK/teach.img" --modes teach > /dev/null
"$BIN/seqslam-firmware" --disk "$WORK/teach.img" > "$WORK/teach.log"
grep -q "^app: captures $places\$" "$WORK/teach.log" || fail "firmware captures != $places places: $(grep captures "$WORK/teach.log")"
grep -q "^app: trigger without frame 0\$" "$WORK/teach.log" || fail "firmware triggered without a frame"
grep -q "^app: places taught $places\$" "$WORK/teach.log" || fail "not every place taught"
echo "firmware: captured and taught all $places simulated places"

# Repeat on the query run and score it.
"$BIN/seqslam" disk export "$WORK/teach.img" library "$WORK/library.bin" > /dev/null
"$BIN/seqslam" disk export "$WORK/teach.img" library.img "$WORK/library.img.bin" > /dev/null
"$BIN/seqslam" disk create "$WORK/repeat.img" --file config:4K \
  --file "replay::$WORK/a/short_morning-lamps.dream" --file "library::$WORK/library.bin" \
  --file "library.img::$WORK/library.img.bin" --file results:64K --file queries:256K > /dev/null
"$BIN/seqslam" config write "$WORK/repeat.img" --modes repeat > /dev/null
"$BIN/seqslam-firmware" --disk "$WORK/repeat.img" > "$WORK/repeat.log"
"$BIN/seqslam" results "$WORK/repeat.img" --ground-truth "$WORK/a/short_morning-lamps.gt.csv" \
  --json "$WORK/result.json" > "$WORK/result.txt"
queries=$(sed -n 's/.*"queries": *\([0-9]*\).*/\1/p' "$WORK/result.json")
qplaces=$(awk -F, '$1 == "short_morning-lamps" {print $3}' "$WORK/a/runs.csv")
[ "$queries" = "$((qplaces - 29))" ] || fail "scored $queries queries, expected $((qplaces - 29))"
echo "repeat scored: $(grep 'top-1' "$WORK/result.txt")"

# Bad input: clear messages, non-zero exits, no crash.
expect_error() {
  local pattern=$1; shift
  if "$@" > "$WORK/out.txt" 2>&1; then fail "succeeded: $*"; fi
  grep -q "$pattern" "$WORK/out.txt" || fail "no '$pattern' in: $(cat "$WORK/out.txt")"
}
expect_error "unknown scenario 'nope'" "$BIN/seqslam-sim" generate --scenario nope --out "$WORK/x"
expect_error "exceeds the pixel buffer" "$BIN/seqslam-sim" generate --size 64x32 --out "$WORK/x"
expect_error "unknown light condition 'noon'" "$BIN/seqslam-sim" generate --library-light noon --out "$WORK/x"
expect_error "nothing/pairs.csv: no such file (generate a scenario first)" "$BIN/seqslam-sim" evaluate \
  "$WORK/nothing"
printf 'library,query,ground_truth,description\nonly-two,fields\n' > "$WORK/a/pairs.csv"
expect_error "pairs.csv:2: expected" "$BIN/seqslam-sim" evaluate "$WORK/a"
head -c 3000 "$WORK/b/short_noon-lamps.dream" > "$WORK/cut.dream"
expect_error "cut.dream" "$BIN/seqslam-sim" truth "$WORK/cut.dream" "$WORK/b/short_noon-lamps.dream" --out "$WORK/t.csv"
echo "bad inputs refused with messages"
