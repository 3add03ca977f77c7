# disk create / list / export / import round trips.
source "$(dirname "$0")/lib.sh"

seq 1 1000 >payload.bin # 3893 bytes
n=$(stat -c %s payload.bin)

ok "$SEQSLAM" disk create disk.img --size 1M --file config:1K --file replay:8K:payload.bin \
  --file results:4000
out_has "^disk.img: 2048 blocks \(1048576 bytes\), 3 files, 2021 blocks unused"
size_is disk.img 1048576
ok "$SEQSLAM" disk list disk.img
out_has "^disk.img: 2048 blocks \(1048576 bytes\), 3 files, 2021 blocks unused" \
  "^name +first +blocks +bytes +contents" \
  "^config +1 +2 +1024 +empty \(zeros\)" \
  "^replay +3 +16 +8192 +unknown data" \
  "^results +19 +8 +4096 +empty \(zeros\)"

# Export: the whole region, i.e. the imported bytes padded (here with the zeros of a new image).
ok "$SEQSLAM" disk export disk.img replay exported.bin
size_is exported.bin 8192
{
  cat payload.bin
  head -c $((8192 - n)) /dev/zero
} >expected.bin
same expected.bin exported.bin

# Import a shorter file: it replaces the first bytes, the rest of the region stays as it was.
printf 'hello, volume' >short.bin
ok "$SEQSLAM" disk import disk.img replay short.bin
ok "$SEQSLAM" disk export disk.img replay exported2.bin
{
  cat short.bin
  tail -c +14 expected.bin
} >expected2.bin
same expected2.bin exported2.bin

# Import a file that fills the region exactly, then export it back.
head -c 8192 /dev/urandom >full.bin
ok "$SEQSLAM" disk import disk.img replay full.bin
ok "$SEQSLAM" disk export disk.img replay exported3.bin
same full.bin exported3.bin
# Neighbours untouched.
ok "$SEQSLAM" disk export disk.img results results.bin
same results.bin <(head -c 4096 /dev/zero)

# Default --size: the file table block plus the files, rounded up to blocks.
ok "$SEQSLAM" disk create small.img --file a:1 --file b:513 --file c:1k
size_is small.img $(((1 + 1 + 2 + 2) * 512))

# What list recognises: a dream recording, a run configuration, a place library, results.
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 16x8
"$CLI_FIXTURES" results res.bin 12 res.csv
"$CLI_FIXTURES" library lib.bin lib.img
ok "$SEQSLAM" disk create sd.img --file config:1K --file replay::ref.dream --file library:8K \
  --file library.img:8K --file results::res.bin --file record:64K
ok "$SEQSLAM" disk import sd.img library lib.bin
ok "$SEQSLAM" disk import sd.img library.img lib.img
ok "$SEQSLAM" config write sd.img --modes teach,repeat --size 16x8
ok "$SEQSLAM" disk list sd.img
out_has "^config .* run config: modes teach,repeat, trigger distance every 0.2 m, 16x8, he-pn, S=30 W=50 R=10, threshold 0.85$" \
  "^replay .* dream recording \(reduced, 16x8\): session [0-9]+, 111 records, ends cleanly$" \
  "^library .* library metadata \(32x16, he\): session [0-9]+, 5 places, ends cleanly$" \
  "^library.img .* library images \(32x16\): session [0-9]+, room for 15 images$" \
  "^results .* results: session [0-9]+, 12 results, ends cleanly$" \
  "^record .* empty \(zeros\)$"
# Without --size, config write takes the replay's mapping (its images are that size) and says
# so; the card's config then holds what --size 16x8 wrote.
ok "$SEQSLAM" config show sd.img
cp out.txt given.txt
ok "$SEQSLAM" config write sd.img --modes teach,repeat
out_has "^sd.img: image size 16x8 and mapping from the card's replay \(--size to choose\)$" \
  "^sd.img:config: modes teach,repeat, trigger distance every 0.2 m, 16x8, he-pn, S=30 W=50 R=10, threshold 0.85$"
ok "$SEQSLAM" config show sd.img
same given.txt out.txt
# Route-search settings other than the defaults are part of the run config's line.
ok "$SEQSLAM" config write sd.img --modes repeat --size 16x8 --start unknown --route-growth 0.1
ok "$SEQSLAM" disk list sd.img
out_has "^config .* run config: modes repeat, trigger distance every 0.2 m, 16x8, he-pn, S=30 W=50 R=10, threshold 0.85, route window=25 slack=2 growth=0.1 lost-after=30 scan-places=1024 scan-seq-len=10 start=unknown$"
echo PASS
