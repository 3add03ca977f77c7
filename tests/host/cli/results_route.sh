# results of the firmware's route search: the PC firmware (seqslam-firmware, the head board's
# app.cpp) teaches the corridor's reference run and repeats its query run from an unknown
# start; `seqslam results` shows the route flags it stored, and its route summary equals the
# firmware's own counters. Usage: results_route.sh SEQSLAM_FIRMWARE
source "$(dirname "$0")/lib.sh"
FIRMWARE=${1:?seqslam-firmware}

ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 16x8
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/query" query.dream --size 16x8
ok "$SEQSLAM" disk create teach.img --file config:1K --file replay::ref.dream --file library:64K \
  --file library.img:64K
ok "$SEQSLAM" config write teach.img --modes teach --trigger every-frame --size 16x8 --seq-len 10 \
  --window 20
ok "$FIRMWARE" --disk teach.img
ok "$SEQSLAM" disk export teach.img library library.bin
ok "$SEQSLAM" disk export teach.img library.img library_img.bin

# A repeat card without the query history: the firmware says which file is missing.
ok "$SEQSLAM" disk create noq.img --file config:1K --file replay::query.dream \
  --file library::library.bin --file library.img::library_img.bin --file results:64K
ok "$SEQSLAM" config write noq.img --modes repeat --trigger every-frame --size 16x8 --seq-len 10 \
  --window 20
run "$FIRMWARE" --disk noq.img
[[ $status -ne 0 ]] || die "the firmware ran a repeat card without a 'queries' file"
grep -q "'queries' file" out.txt err.txt || {
  show
  die "the firmware does not name the 'queries' file"
}

# counter NAME: the firmware's "app: NAME N" line in fw.txt.
counter() {
  sed -n "s/^app: $1 \([0-9][0-9]*\)$/\1/p" fw.txt
}

# check_run IMAGE: the results' route summary equals the firmware's counters (fw.txt), and
# the table's and the CSV's letters count the same.
check_run() {
  local image=$1 scans jumps carried localised
  scans=$(counter "relocalisation scans")
  jumps=$(counter "scan jumps")
  carried=$(counter "carried answers")
  localised=$(counter "localised")
  [[ -n $scans && -n $jumps && -n $carried && -n $localised ]] || die "counters missing in fw.txt"
  ok "$SEQSLAM" results "$image"
  out_has " localised +route$" \
    "^[0-9]+ results \($localised localised\), 0 damaged records; the log ends cleanly$" \
    "^route search: scans completed $scans, jumps $jumps, carried answers $carried; "
  ok "$SEQSLAM" results "$image" --csv "$image.csv"
  head -n 1 "$image.csv" | grep -q ',localised,route$' || die "CSV header without route"
  # Letters of the last column: s = scans completed, J = jumps, C = carried answers.
  local s j c
  s=$(tail -n +2 "$image.csv" | awk -F, '$13 ~ /s/' | wc -l)
  j=$(tail -n +2 "$image.csv" | awk -F, '$13 ~ /J/' | wc -l)
  c=$(tail -n +2 "$image.csv" | awk -F, '$13 ~ /C/' | wc -l)
  [[ $s -eq $scans && $j -eq $jumps && $c -eq $carried ]] ||
    die "CSV letters s=$s J=$j C=$c, firmware $scans $jumps $carried"
  # Every letter is one of the documented ones.
  ! tail -n +2 "$image.csv" | awk -F, '{print $13}' | grep -qv '^\(-\|T\?P\?S\?s\?J\?C\?\)$' ||
    die "undocumented route letters in $image.csv"
}

# Repeat from an unknown start: scans, a jump, probation, tracking.
ok "$SEQSLAM" disk create repeat.img --file config:1K --file replay::query.dream \
  --file library::library.bin --file library.img::library_img.bin --file results:64K \
  --file queries:256K
ok "$SEQSLAM" config write repeat.img --modes repeat --trigger every-frame --size 16x8 \
  --seq-len 10 --window 20 --start unknown --lost-after 5
ok "$FIRMWARE" --disk repeat.img
cp out.txt fw.txt
[[ $(counter "relocalisation scans") -gt 0 && $(counter "scan jumps") -gt 0 ]] ||
  die "the unknown start should need a scan and a jump"
check_run repeat.img
ok "$SEQSLAM" results repeat.img
out_has " T[PSsJC]*$" " TP[SsJC]*$" "SsJ$"

# The route search withholds answers (no prediction, probation, carried): 'localised' 0
# below the threshold is not a sign of another threshold.
ok "$SEQSLAM" results repeat.img --ground-truth "$DATA/corridor/ground_truth.csv"
out_has "^route search: scans completed " "^threshold 0.85: the run configuration repeat.img:config$"
[[ ! -s err.txt ]] || die "unexpected warning: $(cat err.txt)"
# ... and they are not accepted at the threshold, whatever their confidence (they rank after
# every other answer, as in seqslam eval --search route): accepted = the board's localised.
localised=$(counter "localised")
out_has "^at threshold 0.85: $localised accepted, "
# ... but a threshold changed after the run still is.
ok "$SEQSLAM" config write repeat.img --modes repeat --trigger every-frame --size 16x8 \
  --seq-len 10 --window 20 --threshold 0.5
ok "$SEQSLAM" results repeat.img --ground-truth "$DATA/corridor/ground_truth.csv"
err_has "results disagree on 'localised' with threshold 0.5"

# Loop closure (teach + repeat in one run) starts unknown: carried answers after jumps.
ok "$SEQSLAM" disk create loop.img --file config:1K --file replay::ref.dream --file library:64K \
  --file library.img:64K --file results:64K --file queries:256K
ok "$SEQSLAM" config write loop.img --modes teach,repeat --trigger every-frame --size 16x8 \
  --seq-len 10 --window 20
ok "$FIRMWARE" --disk loop.img
cp out.txt fw.txt
check_run loop.img
echo PASS
