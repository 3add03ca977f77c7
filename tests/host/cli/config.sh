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
  "^options: --modes teach,repeat,record --trigger every-frame --size 25x20 --preprocess igk-pn --seq-len 20 --window 0 --exclusion 7 --threshold 0.9 --sigma-min 2.5 --max-shift 3 --recent-exclusion 40 --spacing 0.25 --matcher heuristic --k 7 --guard 3 --candidate-threshold 35.5 --record-colour$"

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
out_has "^options: --modes repeat --trigger distance --size 32x16 --preprocess he --seq-len 30 --window 50 --exclusion 10 --threshold 0.85 --sigma-min 1 --max-shift 0 --recent-exclusion 50 --spacing 0.2 --matcher diagonal --k 5 --guard 5 --candidate-threshold 40$" \
  "matcher +diagonal" "heuristic +k 5 candidates, guard 5 places, candidate threshold 40 grey levels per pixel \(not used\)$"

# The diagonal matcher stays implicit in the summary line; the heuristic's settings are
# stored (and reproduced) with it, unused.
ok "$SEQSLAM" config write c.img --k 16 --guard 1 --candidate-threshold 0
out_has "^c.img:config: modes repeat, trigger distance every 0.2 m, 32x16, he, S=30 W=50 R=10, threshold 0.85$"
ok "$SEQSLAM" config show c.img
out_has "options: .* --matcher diagonal --k 16 --guard 1 --candidate-threshold 0$"

# Writing again replaces the configuration.
ok "$SEQSLAM" config write c.img --modes record --threshold 0.5
ok "$SEQSLAM" config show c.img
out_has "modes +record$" "threshold +0.5 "

# A config file too small for a log header and a record.
ok "$SEQSLAM" disk create tiny.img --file config:512
expect 1 "tiny.img:config: the volume file is too small for a run configuration" \
  "$SEQSLAM" config write tiny.img
# An empty config file.
ok "$SEQSLAM" disk create empty.img --file config:1K
expect 1 "empty.img:config: not a usable run configuration: not a log of the expected kind" \
  "$SEQSLAM" config show empty.img
echo PASS
