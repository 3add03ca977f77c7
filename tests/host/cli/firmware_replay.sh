# The firmware on damaged or unsuitable replays ends with a clear status, never a hang or a
# quiet "run complete": a reduced recording (no odometry) with the distance trigger is refused
# at start (it once looped forever on the same place); a replay with a damaged record is run
# to its end, then reported ("damaged replay records") and the run fails; a replay cut short
# reports the lost records the same way; recording colour from a grey replay is refused.
# Usage: firmware_replay.sh SEQSLAM_FIRMWARE
source "$(dirname "$0")/lib.sh"
FIRMWARE=${1:?seqslam-firmware}
[[ -x $FIRMWARE ]] || die "$FIRMWARE not built (cmake --build ... --target seqslam-firmware)"
REF="$DATA/corridor/ref"

ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
make_disk() {  # make_disk IMAGE REPLAY
  ok "$SEQSLAM" disk create "$1" --file config:1K --file "replay::$2" --file library:64K \
    --file library.img:128K --file results:64K --file queries:512K
}

# Distance trigger (the default) on a reduced recording: refused at start, in bounded time.
make_disk a.img ref.dream
ok "$SEQSLAM" config write a.img --modes teach
expect 2 "" timeout 20 "$FIRMWARE" --disk a.img
out_has "the replay has no odometry \(reduced\): use trigger every-frame"
# The same with every-frame: runs and captures every place.
ok "$SEQSLAM" config write a.img --modes teach --trigger every-frame
ok timeout 20 "$FIRMWARE" --disk a.img
out_has "^app: captures 111$" "^app: damaged replay records 0$" "^host: run complete$"
# The same run with its report lost (standard output on /dev/full): status 1, said on stderr.
if [[ -c /dev/full ]]; then
  set +e
  timeout 20 "$FIRMWARE" --disk a.img >/dev/full 2>err.txt
  status=$?
  set -e
  [[ $status -eq 1 ]] && grep -q "seqslam-firmware: writing standard output: No space left" err.txt ||
    { cat err.txt >&2; die "a lost report exited $status"; }
fi

# One damaged place record in the middle: the rest is used, the damage reported, status 1.
cp ref.dream damaged.dream
flip_byte damaged.dream $((1536 + 548 * 40 + 100))
make_disk b.img damaged.dream
ok "$SEQSLAM" config write b.img --modes teach --trigger every-frame
expect 1 "" timeout 20 "$FIRMWARE" --disk b.img
out_has "^app: captures 110$" "^app: damaged replay records 1$" \
  "data lost: damaged replay records or storage errors" "^host: run failed$"

# Cut at a block boundary: the places before the cut are used, the loss reported, status 1.
head -c $((512 * 40)) ref.dream >cut.dream
make_disk c.img cut.dream
ok "$SEQSLAM" config write c.img --modes teach --trigger every-frame
expect 1 "" timeout 20 "$FIRMWARE" --disk c.img
out_has "^app: damaged replay records 1$" "^host: run failed$"

# Recording in colour from a grey replay: refused at start, not a recording silently lost.
ok "$SEQSLAM" disk create d.img --file config:1K --file replay::ref.dream --file record:256K
ok "$SEQSLAM" config write d.img --modes record --trigger every-frame --record-colour
expect 2 "" timeout 20 "$FIRMWARE" --disk d.img
out_has "record-colour: the replay has no colour to record"
echo PASS
