# images -> dream -> images reproduces the reduced images exactly (against a reduction made
# without the tool), and images -> dream is reproducible byte for byte.
source "$(dirname "$0")/lib.sh"
REF="$DATA/corridor/ref"

ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
out_has "^ref.dream: 111 places of 32x16 pixels \(reduced recording\)"
# Sized to fit: header block, two commit slots + 111 records of 20 + 16 + 512 bytes, rounded
# up to blocks (docs/dream_format.md, "Record log").
size_is ref.dream $(((1536 + 111 * (20 + 16 + 512) + 511) / 512 * 512))

ok "$SEQSLAM" convert dream-to-images ref.dream images --format pgm --index images/index.txt
out_has "111 places of 32x16 pixels written as pgm, 0 snapshots not written, 0 damaged"
mkdir reference
"$CLI_FIXTURES" reduce "$REF" 32 16 reference
n=0
for f in reference/*.pgm; do
  same "$f" "images/${f#reference/}"
  n=$((n + 1))
done
[[ $n -eq 111 ]] || die "expected 111 reference images, got $n"
[[ $(ls images/*.pgm | wc -l) -eq 111 ]] || die "expected 111 images written"
[[ $(wc -l <images/index.txt) -eq 111 ]] || die "index.txt should list 111 images"
[[ $(head -n 1 images/index.txt) == place_000000.pgm ]] || die "index.txt: relative paths in order"
[[ $(tail -n 1 images/index.txt) == place_000110.pgm ]] || die "index.txt: last entry"

# Back again from the index file and from PNGs: the same recording, byte for byte (32x16 ->
# 32x16 is the identity, a new file gets the same session).
ok "$SEQSLAM" convert images-to-dream images/index.txt again.dream --size 32x16
same ref.dream again.dream
ok "$SEQSLAM" convert dream-to-images ref.dream png
[[ -f png/place_000110.png ]] || die "png/place_000110.png missing"
ok "$SEQSLAM" convert images-to-dream png png.dream --size 32x16
same ref.dream png.dream

# A recording inside a disk image, read as IMAGE:NAME.
ok "$SEQSLAM" disk create disk.img --file replay::ref.dream --file spare:4K
ok "$SEQSLAM" convert dream-to-images disk.img:replay fromdisk --format pgm
for f in reference/*.pgm; do
  same "$f" "fromdisk/${f#reference/}"
done

ok "$SEQSLAM" dream info ref.dream
out_has "variant +reduced" "image size +32x16 pixels" "snapshots +0$" "places +111$" \
  "missed snapshots +0 " "damaged records +0$" "log end +ends cleanly" \
  "time span +1.100000 s \(first timestamp 0 us, last 1100000 us\)"
ok "$SEQSLAM" dream info disk.img:replay
out_has "^disk.img:replay: dream recording" "places +111$"

# Another size and timestamp step.
ok "$SEQSLAM" convert images-to-dream "$REF" small.dream --size 16x8 --interval-us 50000
ok "$SEQSLAM" dream info small.dream
out_has "image size +16x8 pixels" "time span +5.500000 s"

# Timestamps are the bus's 32-bit microsecond clock: a recording that wraps it (40 s x 110
# steps = 4 400 s, the clock wraps after 4 294.967296 s) keeps every interval, so the span is
# whole (the robot's clock wraps the same way). A step of 2^31 us or more would read as a step
# back in time (dream info warns about those, issue 34): refused.
ok "$SEQSLAM" convert images-to-dream "$REF" wrap.dream --size 16x8 --interval-us 40000000
ok "$SEQSLAM" dream info wrap.dream
out_has "time span +4400.000000 s \(first timestamp 0 us, last 105032704 us\)"
[[ ! -s err.txt ]] || die "a clock that wraps forward was warned about"
expect 2 "--interval-us: '2147483648' is not within 0..2147483647" \
  "$SEQSLAM" convert images-to-dream "$REF" long.dream --size 16x8 --interval-us 2147483648
echo PASS
