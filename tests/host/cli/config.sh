# config write / show round trip.
source "$(dirname "$0")/lib.sh"

ok "$SEQSLAM" disk create a.img --file config:1K
ok "$SEQSLAM" config write a.img --modes teach,repeat,record --trigger every-frame --size 25x20 \
  --preprocess igk-pn --seq-len 20 --window 0 --exclusion 7 --threshold 0.9 --sigma-min 2.5 \
  --max-shift 3 --recent-exclusion 40 --spacing 0.25 --record-colour --matcher heuristic --k 7 \
  --guard 3 --candidate-threshold 35.5
out_has "^a.img:config: modes teach,repeat,record, trigger every-frame, 25x20, igk-pn, S=20 W=0 R=7, threshold 0.9, heuristic matcher k=7 guard=3 candidate threshold 35.5$"
ok "$SEQSLAM" config show a.img
out_has "^a.img:config$" "modes +teach, repeat, record$" "trigger +every-frame" \
  "spacing +0.25 m$" "image size +25x20 pixels$" "plain reduction" "preprocessing +igk-pn$" \
  "sequence length +20 places" "window +0 places" "exclusion +7 places" "threshold +0.9 " \
  "sigma min +2.5 grey levels$" "max shift +3 pixels$" "recent exclusion +40 places$" \
  "record colour +yes$" "matcher +heuristic \(greedy" \
  "heuristic +k 7 candidates, guard 3 places, candidate threshold 35.5 grey levels per pixel$" \
  "^options: --modes teach,repeat,record --trigger every-frame --size 25x20 --preprocess igk-pn --seq-len 20 --window 0 --exclusion 7 --threshold 0.9 --sigma-min 2.5 --max-shift 3 --recent-exclusion 40 --spacing 0.25 --matcher heuristic --k 7 --guard 3 --candidate-threshold 35.5 --grid-origin -40,-40 --grid-size 1600x1600 --grid-cell 50 --record-colour$"

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
out_has "^options: --modes repeat --trigger distance --size 32x16 --preprocess he --seq-len 30 --window 50 --exclusion 10 --threshold 0.85 --sigma-min 1 --max-shift 0 --recent-exclusion 50 --spacing 0.2 --matcher diagonal --k 5 --guard 5 --candidate-threshold 40 --grid-origin -40,-40 --grid-size 1600x1600 --grid-cell 50$" \
  "matcher +diagonal" "heuristic +k 5 candidates, guard 5 places, candidate threshold 40 grey levels per pixel \(not used\)$"

# The diagonal matcher stays implicit in the summary line; the heuristic's settings are
# stored (and reproduced) with it, unused.
ok "$SEQSLAM" config write c.img --k 16 --guard 1 --candidate-threshold 0
out_has "^c.img:config: modes repeat, trigger distance every 0.2 m, 32x16, he, S=30 W=50 R=10, threshold 0.85$"
ok "$SEQSLAM" config show c.img
out_has "options: .* --matcher diagonal --k 16 --guard 1 --candidate-threshold 0 --grid-origin -40,-40 --grid-size 1600x1600 --grid-cell 50$"

# Writing again replaces the configuration.
ok "$SEQSLAM" config write c.img --modes record --threshold 0.5
ok "$SEQSLAM" config show c.img
out_has "modes +record$" "threshold +0.5 "

# Explore (teach + repeat + mapping) and its map grid; the printed options reproduce it.
ok "$SEQSLAM" disk create x.img --file config:1K
ok "$SEQSLAM" config write x.img --modes explore,record --grid-origin -12.5,3.25 --grid-size 400x300 \
  --grid-cell 100
out_has "^x.img:config: modes record,explore, trigger distance every 0.2 m, .*map origin \(-12.5,3.25\) m 400x300 cells of 100 mm"
ok "$SEQSLAM" config show x.img
out_has "modes +record, explore$" "map grid +origin \(-12.5,3.25\) m, 400x300 cells of 100 mm$" \
  "options: --modes record,explore .* --grid-origin -12.5,3.25 --grid-size 400x300 --grid-cell 100$"
read -r -a options <<<"$(sed -n 's/^options: //p' out.txt)"
ok "$SEQSLAM" disk create y.img --file config:1K
ok "$SEQSLAM" config write y.img "${options[@]}"
ok "$SEQSLAM" disk export x.img config x.bin
ok "$SEQSLAM" disk export y.img config y.bin
same x.bin y.bin
# Explore needs odometry; the grid's ranges are checked.
expect 2 "--modes explore needs --trigger distance" \
  "$SEQSLAM" config write c.img --modes explore --trigger every-frame
expect 2 "invalid grid: grid.cell_mm must be 10..1000" "$SEQSLAM" config write c.img --grid-cell 5
expect 2 "--grid-size: '0x10' is not WxH cells" "$SEQSLAM" config write c.img --grid-size 0x10
expect 2 "--grid-origin: 'a' is not a decimal number" "$SEQSLAM" config write c.img --grid-origin a,1
expect 2 "--grid-origin: '0.0001' is finer than a millimetre" \
  "$SEQSLAM" config write c.img --grid-origin 0.0001,1

# A config file too small for a log header and a record.
ok "$SEQSLAM" disk create tiny.img --file config:512
expect 1 "tiny.img:config: the volume file is too small for a run configuration" \
  "$SEQSLAM" config write tiny.img
# An empty config file.
ok "$SEQSLAM" disk create empty.img --file config:1K
expect 1 "empty.img:config: not a usable run configuration: not a log of the expected kind" \
  "$SEQSLAM" config show empty.img
echo PASS
