#!/usr/bin/env bash
# Teach and repeat a simulated route on the emulated head board (seqslam_fw_app.elf under
# QEMU, the library on the virtio card) and on the PC build of the same application
# (seqslam-firmware); both runs must leave byte-identical disk images and make the same card
# requests (the `card:` lines). Then the repeat's results are scored against the simulator's
# ground truth. docs/firmware.md, "Teach and repeat a whole route on the board".
#
# Used by ctest (firmware_app_lap.qemu: the ~90 m lap of the default scenario, ~450 places)
# and by `make board-route` (the ~1 km route scenario, ~5 000 places; it takes minutes).
#
# Usage: board-teach-repeat.sh --scenario default|route --work DIR --host-bin DIR --board ELF
#          [--seed N] [--min-top1 PERCENT]
#   --host-bin: the host build's bin/ (seqslam, seqslam-sim, seqslam-firmware)
#   --min-top1: fail unless the repeat's top-1 (no threshold) reaches this (default 0: report)
# Output: the board's report lines, the comparison and the scores; summary.txt in DIR.
set -euo pipefail
scenario=default
seed=1
min_top1=0
work=""
host_bin=""
board=""
while [ $# -gt 0 ]; do
  case $1 in
    --scenario) scenario=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --host-bin) host_bin=$2; shift 2 ;;
    --board) board=$2; shift 2 ;;
    --min-top1) min_top1=$2; shift 2 ;;
    *) echo "board-teach-repeat: unknown argument $1" >&2; exit 2 ;;
  esac
done
if [ -z "$work" ] || [ -z "$host_bin" ] || [ -z "$board" ]; then
  echo "usage: board-teach-repeat.sh --scenario default|route --work DIR --host-bin DIR --board ELF" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
host_bin=$(cd "$host_bin" && pwd)
board=$(cd "$(dirname "$board")" && pwd)/$(basename "$board")
seqslam=$host_bin/seqslam
sim=$host_bin/seqslam-sim
firmware=$host_bin/seqslam-firmware
for tool in "$seqslam" "$sim" "$firmware" "$board"; do
  [ -e "$tool" ] || { echo "board-teach-repeat: $tool is missing (build it first)" >&2; exit 2; }
done
die() { echo "board-teach-repeat: FAIL: $*" >&2; exit 1; }

rm -rf "$work"
mkdir -p "$work"
cd "$work"
# One library run and one query run (the query light: the scenario's default,
# morning-lamps).
case $scenario in
  default) "$sim" generate --scenario default --lights morning-lamps --seed "$seed" --out sim ;;
  route) "$sim" generate --scenario route --seed "$seed" --out sim ;;
  *) echo "board-teach-repeat: --scenario default|route" >&2; exit 2 ;;
esac
IFS=, read -r library query truth _ < <(sed -n 2p sim/pairs.csv)
places() { awk -F, -v r="${1%.dream}" '$1 == r { print $3 }' sim/runs.csv; }
lib_places=$(places "$library")
query_places=$(places "$query")
echo "library $library: $lib_places places; query $query: $query_places places"

# kib BYTES: the size in KiB rounded up, as `seqslam disk create` takes it.
kib() { echo $((($1 + 1023) / 1024))K; }
# Files sized for the run (docs/firmware.md, "Files on the card"): library metadata ~48 bytes
# a place (+ margin), images 512 bytes a place + the header block, results ~140 bytes a step.
meta_size=$(kib $((64 * lib_places + 65536)))
images_size=$(kib $((512 * (lib_places + 16) + 512)))
results_size=$(kib $((160 * query_places + 65536)))

# board_and_host NAME: runs the board and the PC build on copies of NAME.img; the images and
# the card request counts must be identical.
board_and_host() {
  local name=$1
  cp "$name.img" "$name.board.img"
  cp "$name.img" "$name.host.img"
  "$here/qemu-run.sh" --disk "$name.board.img" "$board" >"$name.board.txt" ||
    { cat "$name.board.txt"; die "the board's $name run failed"; }
  "$firmware" --disk "$name.host.img" >"$name.host.txt" ||
    { cat "$name.host.txt"; die "the PC's $name run failed"; }
  grep -E "^app: |^card: |^board: " "$name.board.txt"
  grep -q "board: run complete" "$name.board.txt" || die "the board's $name run did not complete"
  cmp -s "$name.img" "$name.board.img" && die "the board wrote nothing ($name)"
  cmp -s "$name.board.img" "$name.host.img" ||
    die "board and PC disk images differ ($name): $(cmp "$name.board.img" "$name.host.img" || true)"
  local board_card host_card
  board_card=$(grep "^card: " "$name.board.txt")
  host_card=$(grep "^card: " "$name.host.txt")
  [ "$board_card" = "$host_card" ] ||
    die "board and PC made different card requests ($name): '$board_card' vs '$host_card'"
  echo "$name: board and PC disk images identical ($(sha256sum <"$name.board.img" | cut -c1-16)), card requests identical; $(grep '^host: card time' "$name.host.txt")"
}

"$seqslam" disk create teach.img --file config:1K --file "replay::sim/$library" \
  --file "library:$meta_size" --file "library.img:$images_size" >/dev/null
"$seqslam" config write teach.img --modes teach >/dev/null
board_and_host teach
"$seqslam" disk export teach.board.img library library.bin >/dev/null
"$seqslam" disk export teach.board.img library.img library_img.bin >/dev/null

"$seqslam" disk create repeat.img --file config:1K --file "replay::sim/$query" \
  --file library::library.bin --file library.img::library_img.bin \
  --file "results:$results_size" --file queries:256K >/dev/null
"$seqslam" config write repeat.img --modes repeat >/dev/null
board_and_host repeat

"$seqslam" results repeat.board.img --ground-truth "sim/$truth" | tee scores.txt
"$seqslam" results repeat.board.img --ground-truth "sim/$truth" --json scores.json >/dev/null
python3 - "$min_top1" scores.json repeat.board.txt teach.board.txt <<'EOF' | tee summary.txt
import json, re, sys
min_top1, scores, repeat, teach = float(sys.argv[1]), json.load(open(sys.argv[2])), open(sys.argv[3]).read(), open(sys.argv[4]).read()
def board(text):
    m = re.search(r"board: RAM used (\d+) of (\d+) bytes \(stack reserved (\d+), high-water (\d+)\)", text)
    return [int(x) for x in m.groups()]
for name, text in (("teach", teach), ("repeat", repeat)):
    used, cap, reserved, high = board(text)
    print(f"{name}: RAM {used} of {cap} bytes, stack high-water {high} of {reserved} reserved")
    assert used <= cap and high <= reserved, name
top1 = 100 * scores["top1"]
print(f"repeat: top-1 {top1:.1f} %, recall at 100 % precision {100 * scores['recall_at_100_precision']:.1f} %, "
      f"precision {100 * scores['precision']:.1f} % / recall {100 * scores['recall']:.1f} % at {scores['threshold']}")
if top1 < min_top1:
    sys.exit(f"board-teach-repeat: FAIL: top-1 {top1:.1f} % below {min_top1} %")
EOF
