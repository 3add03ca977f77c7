# config write against the card's data (issue 34, tools/seqslam/card_checks.h): a start place
# beyond the card's library and a query history too small for the relocalisation scan are
# refused with the card byte for byte as it was; what the firmware refuses at start or counts
# as failed is warned about. The PC firmware is the oracle of the warnings' claims (a scan
# needs ceil(M / scan_places) + scan_seq_len - 1 query steps). Usage: config_card.sh FIRMWARE
source "$(dirname "$0")/lib.sh"
FIRMWARE=${1:?seqslam-firmware}

# A taught card of the corridor's 111 reference places (16x8: quick), its library exported.
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 16x8
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/query" query.dream --size 16x8
ok "$SEQSLAM" disk create teach.img --file config:1K --file replay::ref.dream --file library:64K \
  --file library.img:64K
settings=(--trigger every-frame --size 16x8 --seq-len 10 --window 20)
ok "$SEQSLAM" config write teach.img --modes teach "${settings[@]}"
ok "$FIRMWARE" --disk teach.img
ok "$SEQSLAM" disk export teach.img library library.bin
ok "$SEQSLAM" disk export teach.img library.img library_img.bin

# card NAME QUERIES_BYTES: a repeat card with the taught library and a query history of that
# size.
card() {
  ok "$SEQSLAM" disk create "$1" --file config:1K --file replay::query.dream \
    --file library::library.bin --file library.img::library_img.bin --file results:64K \
    --file "queries:$2"
}
# refused STATUS REGEX IMAGE ARGS...: config write IMAGE ARGS exits STATUS matching REGEX and
# leaves IMAGE unchanged.
refused() {
  local want=$1 regex=$2 image=$3
  shift 3
  cp "$image" before.img
  expect "$want" "$regex" "$SEQSLAM" config write "$image" "$@"
  same before.img "$image"
}

# --start beyond the library (it has places 0..110).
card r.img 256K
for start in 111 5000; do
  refused 2 "^seqslam: error: --start $start: the card's library \(r.img:library\) has 111 places \(0..110\); a repeat run starts at one of them, or give --start unknown$" \
    r.img --modes repeat "${settings[@]}" --start "$start"
done
ok "$SEQSLAM" config write r.img --modes repeat "${settings[@]}" --start 110
[[ ! -s err.txt ]] || die "a start within the library was warned about"
# Teach + repeat starts unknown whatever --start says; a card without a library cannot be
# checked (warned).
ok "$SEQSLAM" config write r.img --modes teach,repeat "${settings[@]}" --start 5000
ok "$SEQSLAM" disk create empty.img --file config:1K --file results:64K --file queries:256K \
  --file library:64K --file library.img:64K
ok "$SEQSLAM" config write empty.img --modes repeat "${settings[@]}" --start 3
err_has "^seqslam: warning: --start 3 is not checked against the card's library: empty.img:library is empty \(zeros\)$"

# A query history too small for the scan to start: 1 and 2 steps, fewer than its 10 images.
for bytes in 512 1K; do
  card "q$bytes.img" "$bytes"
  refused 2 "^seqslam: error: q$bytes.img:queries holds [12] query steps? \(512 bytes each\), fewer than the 10 the relocalisation scan compares" \
    "q$bytes.img" --modes repeat "${settings[@]}" --start unknown
  refused 2 "fewer than the 10 the relocalisation scan compares" \
    "q$bytes.img" --modes teach,repeat "${settings[@]}"
done
# ... and, from an unknown start, too small for a scan over 111 places at 16 a step to finish
# (the default, 1 024 a step, finishes in one):
# 15 steps are one too few, 16 enough. With a known start the card is written with a warning.
card q15.img 7680
refused 2 "^seqslam: error: q15.img:queries holds 15 query steps: a relocalisation scan \(16 places a step, 10 query images\) covers at most \(15 - 10 \+ 1\) x 16 = 96 places before its first images are overwritten, and the library has 111: every scan would be abandoned .* \(with --start unknown nothing would be localised\)$" \
  q15.img --modes repeat "${settings[@]}" --scan-places 16 --start unknown
ok "$SEQSLAM" config write q15.img --modes repeat "${settings[@]}" --scan-places 16 --start 0
err_has "^seqslam: warning: q15.img:queries holds 15 query steps: .* \(tracking from --start 0 still works\)$"
card q16.img 8K
ok "$SEQSLAM" config write q16.img --modes repeat "${settings[@]}" --scan-places 16 --start unknown
[[ ! -s err.txt ]] || die "16 query steps were warned about"
# The firmware agrees: with 16 steps every scan completes; 15 (the refused configuration
# copied over from the 16-step card) it refuses at start with the same reason, before writing
# anything (it ran and abandoned every scan, localising nothing).
ok "$FIRMWARE" --disk q16.img
out_has "^app: scan card errors 0$" "^app: relocalisation scans [1-9]" "^app: localised [1-9]"
ok "$SEQSLAM" disk export q16.img config config.bin
ok "$SEQSLAM" disk import q15.img config config.bin
cp q15.img q15.orig
expect 2 "" "$FIRMWARE" --disk q15.img
out_has "^app: query history: OUT_OF_RANGE - the 'queries' file is too small for a relocalisation scan over this library"
same q15.orig q15.img

# Warned about, written: what the firmware refuses at start with its own sentence.
ok "$SEQSLAM" disk create bare.img --file config:1K --file replay::query.dream \
  --file library::library.bin --file library.img::library_img.bin
ok "$SEQSLAM" config write bare.img --modes repeat,record --record-colour "${settings[@]}"
err_has "^seqslam: warning: bare.img has no 'queries' file: the firmware refuses to start a repeat run without its query history" \
  "^seqslam: warning: bare.img has no 'results' file: the firmware refuses to start with this configuration$" \
  "^seqslam: warning: bare.img has no 'record' file: the firmware refuses to start with this configuration$" \
  "^seqslam: warning: --record-colour: bare.img:replay has no colour to record \(a grey recording\): the firmware refuses to start with this configuration$"
ok "$SEQSLAM" config write bare.img --modes continue
err_has "^seqslam: warning: --modes continue: no saved run to continue \(the card has no 'state' file\): the firmware refuses to start with this configuration$"
echo PASS
