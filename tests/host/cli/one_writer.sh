# One writer at a time, and a card the file size limit would cut refused before it is touched
# (issue 34; hal/host_file.h, output_file.h). Another process writing a file is played by
# flock(1), which holds the file's lock (the same advisory flock the tools take) while it runs
# the command under test: no timing involved. Every refused command exits with its status,
# says the file is in use, and leaves the file byte for byte as it was.
# Usage: one_writer.sh SEQSLAM_FIRMWARE
source "$(dirname "$0")/lib.sh"
FIRMWARE=${1:?seqslam-firmware}
command -v flock >/dev/null || die "flock(1) (util-linux) is needed"
GT="$DATA/corridor/ground_truth.csv"
busy="in use by another process"

no_temporaries() {
  local left
  left=$(find . -maxdepth 1 -name '.*.tmp-*' | head -n 5)
  [[ -z $left ]] || die "temporaries left behind: $left"
}

# locked FILE STATUS CMD...: CMD, run while another process holds FILE's lock, exits with
# STATUS naming FILE as in use, and FILE is unchanged.
locked() {
  local file=$1 want=$2
  shift 2
  cp -- "$file" held.orig
  expect "$want" "$file: $busy" flock "$file" "$@"
  same held.orig "$file"
}

ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 16x8
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/query" query.dream --size 16x8
ok "$SEQSLAM" disk create card.img --file config:1K --file replay::ref.dream --file library:64K \
  --file library.img:64K --file results:64K --file queries:256K
ok "$SEQSLAM" config write card.img --modes teach --trigger every-frame --size 16x8 --seq-len 10 \
  --window 20

# The card: a second firmware, config write, disk import, disk create over it.
locked card.img 2 "$FIRMWARE" --disk card.img
err_has "^seqslam-firmware: card.img: $busy"
locked card.img 1 "$SEQSLAM" config write card.img --modes teach --trigger every-frame \
  --size 16x8 --seq-len 5 --window 20
locked card.img 1 "$SEQSLAM" disk import card.img replay query.dream
locked card.img 1 "$SEQSLAM" disk create card.img --file a:1K
no_temporaries
# Readers are not writers: listing and exporting a card in use still work.
ok flock card.img "$SEQSLAM" disk list card.img
ok flock card.img "$SEQSLAM" disk export card.img replay replay.bin
same ref.dream <(head -c "$(stat -c %s ref.dream)" replay.bin)
# Once the lock is free the same firmware run works.
ok "$FIRMWARE" --disk card.img

# Outputs: an appended sweep (two sweeps at once wrote duplicate rows) and a replaced CSV.
sweep=(sweep --pair ref.dream,query.dream,"$GT" --size 16x8 --quiet --out sweep.csv)
ok "$SEQSLAM" "${sweep[@]}" --seq-len 5
locked sweep.csv 1 "$SEQSLAM" "${sweep[@]}" --seq-len 5,10
ok "$SEQSLAM" "${sweep[@]}" --seq-len 5,10
[[ $(grep -c '' sweep.csv) -eq 3 ]] || die "sweep.csv: expected the header and 2 rows"
ok "$SEQSLAM" run ref.dream query.dream --size 16x8 --csv results.csv
locked results.csv 1 "$SEQSLAM" run ref.dream query.dream --size 16x8 --seq-len 5 --csv results.csv
locked results.csv 1 "$SEQSLAM" eval ref.dream query.dream --size 16x8 --ground-truth "$GT" \
  --json results.csv --quiet
no_temporaries

# The firmware under a file size limit smaller than the card: refused before the first write
# (status 1, the limit named), the card unchanged. SIGXFSZ is not trapped: the program ignores
# it itself.
cp card.img card.orig
expect 1 "^seqslam-firmware: card.img: the file size limit \(ulimit -f\) is 1024 bytes, and writing it needs [0-9]+: File too large" \
  bash -c 'ulimit -f 1 && exec "$0" --disk card.img' "$FIRMWARE"
same card.orig card.img
# ... and so are config write and disk import when the bytes they would write lie beyond it.
expect 1 "^seqslam: error: card.img: the file size limit \(ulimit -f\) is 1024 bytes, and writing it needs [0-9]+: File too large \(volume file 'replay'; nothing was written\)$" \
  bash -c 'ulimit -f 1 && exec "$0" disk import card.img replay query.dream' "$SEQSLAM"
same card.orig card.img
echo PASS
