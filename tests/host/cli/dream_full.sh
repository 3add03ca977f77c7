# dream info and dream-to-images on a full recording (snapshots, places, infrared).
source "$(dirname "$0")/lib.sh"

"$CLI_FIXTURES" full-dream full.dream
ok "$SEQSLAM" dream info full.dream
out_has "variant +full" "image size +8x4 pixels" "camera +346x271 pixels, gamma 0.45" \
  "wheels +4096 ticks/revolution, circumference left 0.532 m, right 0.53227 m, track width 0.474 m" \
  "spacing +0.2 m" "infrared sensors +2:" \
  "#0 at \(120, 40\) mm, pointing 45.00 deg, range 40..300 mm" \
  "#1 at \(120, -40\) mm, pointing -45.00 deg, range 40..300 mm" \
  "head orientation +recorded" "snapshots +10$" "places +3$" "missed snapshots +1 " \
  "damaged records +0$" "log end +ends cleanly" \
  "time span +0.100000 s \(first timestamp 1000000 us, last 1100000 us\)"

ok "$SEQSLAM" convert dream-to-images full.dream images --index list.txt
out_has "3 places of 8x4 pixels written as png, 10 snapshots not written, 0 damaged"
[[ $(cat list.txt) == $'images/place_000000.png\nimages/place_000001.png\nimages/place_000002.png' ]] ||
  die "list.txt: $(cat list.txt)"

# Inside a disk image.
ok "$SEQSLAM" disk create disk.img --file record::full.dream
ok "$SEQSLAM" disk list disk.img
out_has "^record .* dream recording \(full, 8x4\): session [0-9]+, 13 records, ends cleanly$"
ok "$SEQSLAM" dream info disk.img:record
out_has "^disk.img:record: dream recording" "places +3$"
expect 1 "disk.img is a disk image: name the volume file as disk.img:NAME \(the volume has: record\)" \
  "$SEQSLAM" dream info disk.img

# A damaged record in the middle (the second snapshot; snapshot records are 20 bytes of
# framing + 24 + 2 per infrared sensor): reported, the rest read, status 1.
cp full.dream damaged.dream
flip_byte damaged.dream $((1536 + 48 + 30))
expect 1 "damaged.dream: record skipped" "$SEQSLAM" dream info damaged.dream
out_has "damaged records +1$"

# Across the bus's 32-bit sequence wrap (snapshots 4294967290..4 without 4294967293): in
# order, the same as above (issue 34: every snapshot after the wrap was refused as out of
# order). The firmware's replay and seqslam slam read it with the same reader.
"$CLI_FIXTURES" full-dream wrap.dream 4294967290
ok "$SEQSLAM" dream info wrap.dream
out_has "snapshots +10$" "places +3$" "missed snapshots +1 " "damaged records +0$" \
  "time span +0.100000 s \(first timestamp 1000000 us, last 1100000 us\)"
[[ ! -s err.txt ]] || die "a recording across the wrap was warned about"
ok "$SEQSLAM" convert dream-to-images wrap.dream wrap_images
out_has "3 places of 8x4 pixels written as png, 10 snapshots not written, 0 damaged"

# Timestamps that run backwards: the span counts the steps forward, and a warning says so
# (it printed 4296.967296 s, without a word).
"$CLI_FIXTURES" reduced-dream-times back.dream 1000000 2000000 1500000 3000000
ok "$SEQSLAM" dream info back.dream
out_has "time span +2.500000 s \(first timestamp 1000000 us, last 3000000 us; 1 step back in time not counted\)$"
err_has "^seqslam: warning: back.dream: the timestamps run backwards 1 time \(first at place 2: 1500000 us after 2000000 us\); the time span counts only the steps forward$"
# ... while a clock that wraps forward (after 71.6 minutes) is a step forward.
"$CLI_FIXTURES" reduced-dream-times wrapped.dream 4294000000 4294967295 500000
ok "$SEQSLAM" dream info wrapped.dream
out_has "time span +1.467296 s \(first timestamp 4294000000 us, last 500000 us\)$"
[[ ! -s err.txt ]] || die "a clock wrapping forward was warned about"
echo PASS
