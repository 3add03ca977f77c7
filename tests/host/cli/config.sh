# config write / show round trip.
source "$(dirname "$0")/lib.sh"

ok "$SEQSLAM" disk create a.img --file config:1K
ok "$SEQSLAM" config write a.img --modes teach,repeat,record --trigger every-frame --size 25x20 \
  --preprocess igk-pn --seq-len 20 --window 0 --exclusion 7 --threshold 0.9 --sigma-min 2.5 \
  --max-shift 3 --recent-exclusion 40 --spacing 0.25 --record-colour --matcher heuristic --k 7 \
  --guard 3 --candidate-threshold 35.5 --heuristic-scan-places 48 --route-window 17 --route-slack 4 --route-growth 0.125 \
  --lost-after 12 --scan-places 40 --scan-seq-len 25 --start 7
out_has "^a.img:config: modes teach,repeat,record, trigger every-frame, 25x20, igk-pn, S=20 W=0 R=7, threshold 0.9, heuristic matcher k=7 guard=3 candidate threshold 35.5 first-scan-places=48, route window=17 slack=4 growth=0.125 lost-after=12 scan-places=40 scan-seq-len=25 start=7$"
ok "$SEQSLAM" config show a.img
# One row per setting the card carries, in the settings table's order (storage/run_config.h).
out_has "^a.img:config$" "^  modes +teach,repeat,record$" "^  trigger +every-frame \(every recorded frame is a place\)$" \
  "^  spacing +0.25 m$" "^  size +25x20 pixels$" "plain reduction" "^  preprocess +igk-pn$" \
  "^  seq-len +20 places \(S\)$" "^  window +0 places \(W; 0 = no local normalisation\)$" "^  exclusion +7 places \(R\)$" "^  threshold +0.9 \(localised when the confidence is below it\)$" \
  "^  sigma-min +2.5 grey levels$" "^  max-shift +3 pixels$" "^  recent-exclusion +40 places$" \
  "^  record-colour +yes$" "^  matcher +heuristic$" "^  k +7$" "^  guard +3 places$" \
  "^  candidate-threshold +35.5 grey levels per pixel$" "^  heuristic-scan-places +48 places$" \
  "^  route-window +17 diagonals \(not used: not the diagonal matcher\)$" \
  "^  route-slack +4 places \(not used: not the diagonal matcher\)$" \
  "^  route-growth +0.125 places per place \(32/256 = 0.125\) \(not used: not the diagonal matcher\)$" \
  "^  lost-after +12 places \(not used: not the diagonal matcher\)$" \
  "^  scan-places +40 places \(not used: not the diagonal matcher\)$" \
  "^  scan-seq-len +25 steps \(20 used: at most S\) \(not used: not the diagonal matcher\)$" \
  "^  start +place 7 \(not used: not the diagonal matcher\)$" \
  "^options: --modes teach,repeat,record --trigger every-frame --max-shift 3 --record-colour --size 25x20 --preprocess igk-pn --seq-len 20 --window 0 --sigma-min 2.5 --exclusion 7 --threshold 0.9 --recent-exclusion 40 --wheels 0.532,0.53227,0.474 --spacing 0.25 --matcher heuristic --k 7 --guard 3 --candidate-threshold 35.5 --grid-origin -40,-40 --grid-cell 50 --grid-size 1600x1600 --route-window 17 --route-slack 4 --route-growth 0.125 --lost-after 12 --scan-places 40 --scan-seq-len 25 --start 7 --heuristic-scan-places 48$"

# The printed options write the same configuration, byte for byte.
read -r -a options <<<"$(sed -n 's/^options: //p' out.txt)"
ok "$SEQSLAM" disk create b.img --file config:1K
ok "$SEQSLAM" config write b.img "${options[@]}"
ok "$SEQSLAM" disk export a.img config a.bin
ok "$SEQSLAM" disk export b.img config b.bin
same a.bin b.bin

# Defaults are RunConfig's.
ok "$SEQSLAM" disk create c.img --file config:1K
ok "$SEQSLAM" config write c.img
ok "$SEQSLAM" config show c.img
out_has "^options: --modes repeat --trigger distance --max-shift 0 --size 12x10 --preprocess he-pn --seq-len 30 --window 50 --sigma-min 1 --exclusion 10 --threshold 0.85 --recent-exclusion 50 --wheels 0.532,0.53227,0.474 --spacing 0.2 --matcher diagonal --k 5 --guard 5 --candidate-threshold 40 --grid-origin -40,-40 --grid-cell 50 --grid-size 1600x1600 --route-window 25 --route-slack 2 --route-growth 0.05 --lost-after 30 --scan-places 1024 --scan-seq-len 10 --start 0 --heuristic-scan-places 96$" \
  "^  matcher +diagonal$" "^  k +5 \(not used: matcher diagonal\)$" \
  "^  heuristic-scan-places +96 places \(not used: matcher diagonal\)$" \
  "^  route-window +25 diagonals$" "^  route-slack +2 places$" \
  "^  route-growth +0.05 places per place \(13/256 = 0.05078125\)$" "^  lost-after +30 places$" \
  "^  scan-places +1024 places$" "^  scan-seq-len +10 steps$" "^  start +place 0$"
# The defaults are RouteSearchConfig's (given explicitly they write the same bytes), and the
# summary leaves the route search implicit with them.
ok "$SEQSLAM" disk create d1.img --file config:1K
ok "$SEQSLAM" config write d1.img
ok "$SEQSLAM" disk create d2.img --file config:1K
ok "$SEQSLAM" config write d2.img --route-window 25 --route-slack 2 --route-growth 0.05 \
  --lost-after 30 --scan-places 1024 --scan-seq-len 10 --start 0
out_has "^d2.img:config: modes repeat, trigger distance every 0.2 m, 12x10, he-pn, S=30 W=50 R=10, threshold 0.85$"
ok "$SEQSLAM" disk export d1.img config d1.bin
ok "$SEQSLAM" disk export d2.img config d2.bin
same d1.bin d2.bin

# The route search with the diagonal matcher in repeat mode: used, an unknown start, a growth
# that is not a multiple of 1/256 (stored as the nearest step, shown with its exact value),
# and the printed options write the same configuration byte for byte.
ok "$SEQSLAM" disk create r.img --file config:1K
ok "$SEQSLAM" config write r.img --route-window 23 --exclusion 9 --route-slack 0 \
  --route-growth 0.3 --lost-after 1 --scan-places 1 --scan-seq-len 1 --start unknown
out_has "^r.img:config: .* R=9, threshold 0.85, route window=23 slack=0 growth=0.3 lost-after=1 scan-places=1 scan-seq-len=1 start=unknown$"
ok "$SEQSLAM" config show r.img
out_has "^  route-window +23 diagonals$" "^  route-growth +0.3 places per place \(77/256 = 0.30078125\)$" \
  "^  start +unknown \(a scan finds the place first\)$" \
  "options: .* --route-window 23 --route-slack 0 --route-growth 0.3 --lost-after 1 --scan-places 1 --scan-seq-len 1 --start unknown --heuristic-scan-places 96$"
read -r -a options <<<"$(sed -n 's/^options: //p' out.txt)"
ok "$SEQSLAM" disk create r2.img --file config:1K
ok "$SEQSLAM" config write r2.img "${options[@]}"
ok "$SEQSLAM" disk export r.img config r.bin
ok "$SEQSLAM" disk export r2.img config r2.bin
same r.bin r2.bin
# -1 is the unknown start too; growth 0 and the largest UQ8.8 value are kept exactly.
ok "$SEQSLAM" config write r.img --start -1 --route-growth 0
ok "$SEQSLAM" config show r.img
out_has "^  route-growth +0 places per place \(0/256 = 0\)$" "^  start +unknown \(a scan finds the place first\)$" \
  "options: .* --route-growth 0 .* --start unknown "
ok "$SEQSLAM" config write r.img --route-growth 255.998 --start 2147483647
ok "$SEQSLAM" config show r.img
out_has "^  route-growth +255.996 places per place \(65535/256 = 255.99609375\)$" "^  start +place 2147483647$"
# Which modes use it: teach alone and explore do not search it.
ok "$SEQSLAM" config write r.img --modes teach,repeat --start 3
ok "$SEQSLAM" config show r.img
out_has "^  route-window +25 diagonals$" "^  start +place 3 \(not used: teach \+ repeat starts unknown\)$"
ok "$SEQSLAM" config write r.img --modes teach
ok "$SEQSLAM" config show r.img
out_has "^  route-window +25 diagonals \(not used: no repeat mode\)$"
ok "$SEQSLAM" config write r.img --modes explore
ok "$SEQSLAM" config show r.img
out_has "^  route-window +25 .*\(not used: explore runs the full search\)$"

# The diagonal matcher stays implicit in the summary line; the heuristic's settings are
# stored (and reproduced) with it, unused.
ok "$SEQSLAM" config write c.img --k 16 --guard 1 --candidate-threshold 0
out_has "^c.img:config: modes repeat, trigger distance every 0.2 m, 12x10, he-pn, S=30 W=50 R=10, threshold 0.85$"
ok "$SEQSLAM" config show c.img
out_has "options: .* --matcher diagonal --k 16 --guard 1 --candidate-threshold 0 --grid-origin -40,-40 --grid-cell 50 --grid-size 1600x1600 --route-window 25 "

# Writing again replaces the configuration.
ok "$SEQSLAM" config write c.img --modes record --threshold 0.5
ok "$SEQSLAM" config show c.img
out_has "^  modes +record$" "^  threshold +0.5 \(localised when the confidence is below it\)$"

# Explore (teach + repeat + mapping) and its map grid; the printed options reproduce it.
ok "$SEQSLAM" disk create x.img --file config:1K
ok "$SEQSLAM" config write x.img --modes explore,record --grid-origin -12.5,3.25 --grid-size 400x300 \
  --grid-cell 100
out_has "^x.img:config: modes record,explore, trigger distance every 0.2 m, .*map origin \(-12.5,3.25\) m 400x300 cells of 100 mm"
ok "$SEQSLAM" config show x.img
out_has "^  modes +teach,repeat,record,explore$" "^  grid-origin +-12.5,3.25 m$" \
  "^  grid-size +400x300 cells$" "^  grid-cell +100 mm$" \
  "options: --modes teach,repeat,record,explore .* --grid-origin -12.5,3.25 --grid-cell 100 --grid-size 400x300 --route-window 25 "
read -r -a options <<<"$(sed -n 's/^options: //p' out.txt)"
ok "$SEQSLAM" disk create y.img --file config:1K
ok "$SEQSLAM" config write y.img "${options[@]}"
ok "$SEQSLAM" disk export x.img config x.bin
ok "$SEQSLAM" disk export y.img config y.bin
same x.bin y.bin

# Calibrated wheel constants (seqslam slam --calibration-out) persist in the configuration the
# firmware's odometry starts from; the printed options reproduce them byte for byte.
ok "$SEQSLAM" disk create w.img --file config:1K
ok "$SEQSLAM" config write w.img --modes explore --wheels 0.532082806,0.532187152,0.475836012
ok "$SEQSLAM" config show w.img
out_has "^  wheels +0.532082806[0-9]*,0.532187152[0-9]*,0.475836012[0-9]*$" \
  "options: --modes teach,repeat,explore .* --wheels 0.532082806[0-9]*,0.532187152[0-9]*,0.475836012[0-9]*"
read -r -a options <<<"$(sed -n 's/^options: //p' out.txt)"
ok "$SEQSLAM" disk create w2.img --file config:1K
ok "$SEQSLAM" config write w2.img "${options[@]}"
ok "$SEQSLAM" disk export w.img config w.bin
ok "$SEQSLAM" disk export w2.img config w2.bin
same w.bin w2.bin
for bad in 0.532 0.532,0.53227 0.532,0.53227,0 0.532,x,0.474 0.532,0.53227,0.474,1 -1,0.5,0.4; do
  expect 2 "--wheels: '$bad': wants LEFT,RIGHT,TRACK" "$SEQSLAM" config write w.img --wheels "$bad"
done
# Continue: an explore run continued from the card (explore implied).
ok "$SEQSLAM" config write x.img --modes continue
ok "$SEQSLAM" config show x.img
out_has "^  modes +teach,repeat,explore,continue$" "options: --modes teach,repeat,explore,continue "
# Explore needs odometry; the grid's ranges are checked.
expect 2 "--modes explore needs --trigger distance" \
  "$SEQSLAM" config write c.img --modes explore --trigger every-frame
expect 2 "--grid-cell: '5' is not within 10..1000" "$SEQSLAM" config write c.img --grid-cell 5
expect 2 "--grid-size: '0x10' is not WxH cells" "$SEQSLAM" config write c.img --grid-size 0x10
expect 2 "--grid-origin: 'a' is not a decimal" "$SEQSLAM" config write c.img --grid-origin a,1
expect 2 "--grid-origin: '0.0001' is finer than a millimetre" \
  "$SEQSLAM" config write c.img --grid-origin 0.0001,1

# A configuration of an older format version (before the route search: version 3) is
# refused with how to replace it.
"$CLI_FIXTURES" config-version v3.bin 3
ok "$SEQSLAM" disk create v3.img --file config::v3.bin
expect 1 '^seqslam: error: v3.img:config: not a usable run configuration: written by another format version \(this tool reads and writes version 4\): write it again with `seqslam config write`$' \
  "$SEQSLAM" config show v3.img
ok "$SEQSLAM" disk list v3.img
out_has "^config .* run config, unusable: written by another format version \(not version 4: write it again with seqslam config write\)$"
ok "$SEQSLAM" config write v3.img
ok "$SEQSLAM" config show v3.img

# One block holds a run configuration (a header-only log: no commit slots, no records).
ok "$SEQSLAM" disk create tiny.img --file config:512
ok "$SEQSLAM" config write tiny.img
ok "$SEQSLAM" config show tiny.img
# An empty config file.
ok "$SEQSLAM" disk create empty.img --file config:1K
expect 1 "empty.img:config: not a usable run configuration: not a log of the expected kind" \
  "$SEQSLAM" config show empty.img
echo PASS
