#!/usr/bin/env bash
# Scratch disk images for the virtio-blk target test (tests/support/virtio_block_test.cpp).
#
#   make-test-disk.sh create IMAGE BLOCKS
#       Writes a fresh raw image of BLOCKS 512-byte blocks holding the host pattern.
#   make-test-disk.sh verify IMAGE BLOCKS FIRST:COUNT[,FIRST:COUNT...]
#       Checks, with host tools only, that IMAGE is exactly BLOCKS blocks long, that the
#       listed ranges hold the firmware's pattern and every other block still holds the
#       host pattern. On a mismatch prints the first bad block (od) next to the expected
#       one and exits 1.
#   make-test-disk.sh selftest DIR
#       Proves the check can fail: in DIR, a fresh image verifies with no ranges, but not
#       with a range the firmware never wrote, nor after one flipped byte, nor truncated.
#
# Block contents: 32 lines of 16 bytes, "<tag><block, 8 digits> L<line, 2 digits>\n",
# tag "BLK" (written here) or "WRT" (written by the firmware), e.g. "BLK00000042 L07\n".
# Exit status: 0 ok, 1 verification failed, 2 usage or I/O error.
set -euo pipefail

usage() {
  echo "usage: $(basename "$0") create IMAGE BLOCKS" >&2
  echo "       $(basename "$0") verify IMAGE BLOCKS FIRST:COUNT[,FIRST:COUNT...]" >&2
  echo "       $(basename "$0") selftest DIR" >&2
  exit 2
}

# pattern BLOCKS RANGES > file: the whole image as it must be (RANGES may be empty).
pattern() {
  awk -v blocks="$1" -v ranges="$2" 'BEGIN {
    n = split(ranges, list, ",")
    for (i = 1; i <= n; i++) {
      if (split(list[i], r, ":") != 2 || r[1] !~ /^[0-9]+$/ || r[2] !~ /^[0-9]+$/ ||
          r[1] + r[2] > blocks) {
        print "make-test-disk.sh: bad range \"" list[i] "\" for " blocks " blocks" > "/dev/stderr"
        exit 2
      }
      for (b = r[1]; b < r[1] + r[2]; b++) firmware[b] = 1
    }
    for (b = 0; b < blocks; b++) {
      tag = (b in firmware) ? "WRT" : "BLK"
      for (line = 0; line < 32; line++) printf "%s%08d L%02d\n", tag, b, line
    }
  }'
}

if [ $# -eq 2 ] && [ "$1" = "selftest" ]; then
  img="$2/make-test-disk-selftest.img"
  self=$0
  expect() {  # expect STATUS command...: runs the command quietly, checks its status
    local want=$1 got=0
    shift
    "$@" >/dev/null 2>&1 || got=$?
    if [ "$got" -ne "$want" ]; then
      echo "make-test-disk.sh: selftest FAIL: '$*' exited $got, expected $want" >&2
      exit 1
    fi
  }
  expect 0 "$self" create "$img" 16
  expect 0 "$self" verify "$img" 16 ""
  expect 1 "$self" verify "$img" 16 "3:1"             # the "firmware" never wrote block 3
  expect 2 "$self" verify "$img" 16 "15:2"            # range past the end
  printf 'x' | dd of="$img" bs=1 seek=$((7 * 512 + 100)) conv=notrunc status=none
  expect 1 "$self" verify "$img" 16 ""                # one flipped byte in block 7
  expect 0 "$self" create "$img" 16
  truncate -s $((15 * 512)) "$img"
  expect 1 "$self" verify "$img" 16 ""                # a block short
  rm -f "$img"
  echo "make-test-disk.sh: selftest passed (verify catches a missing write, a flipped byte," \
       "a short image)"
  exit 0
fi

[ $# -ge 3 ] || usage
mode=$1
image=$2
blocks=$3
case $blocks in
  ''|*[!0-9]*|0) echo "make-test-disk.sh: BLOCKS must be a positive integer, got '$blocks'" >&2
                 exit 2 ;;
esac

case $mode in
  create)
    [ $# -eq 3 ] || usage
    tmp="$image.tmp.$$"
    pattern "$blocks" "" > "$tmp"
    mv -f "$tmp" "$image"
    echo "make-test-disk.sh: wrote $image ($blocks blocks of the host pattern)"
    ;;
  verify)
    [ $# -eq 4 ] || usage
    ranges=$4  # may be empty: no firmware writes expected
    if [ ! -f "$image" ]; then
      echo "make-test-disk.sh: no image $image" >&2
      exit 2
    fi
    size=$(stat -c %s "$image")
    if [ "$size" -ne $((blocks * 512)) ]; then
      echo "make-test-disk.sh: FAIL: $image is $size bytes, expected $((blocks * 512))" >&2
      exit 1
    fi
    expected=$(mktemp)
    trap 'rm -f "$expected"' EXIT
    pattern "$blocks" "$ranges" > "$expected"
    if diff_at=$(cmp "$image" "$expected" 2>&1); then
      echo "make-test-disk.sh: $image holds the firmware's writes ($ranges) and the host" \
           "pattern elsewhere ($blocks blocks)"
      exit 0
    fi
    echo "make-test-disk.sh: FAIL: $diff_at" >&2
    # cmp reports "... differ: byte N, line M" with N counted from 1.
    byte=$(printf '%s\n' "$diff_at" | sed -n 's/.*byte \([0-9]*\).*/\1/p')
    if [ -n "$byte" ]; then
      block=$(((byte - 1) / 512))
      echo "block $block of the image:" >&2
      od -A d -c -j $((block * 512)) -N 512 "$image" | head -8 >&2
      echo "expected:" >&2
      od -A d -c -j $((block * 512)) -N 512 "$expected" | head -8 >&2
    fi
    exit 1
    ;;
  *)
    usage
    ;;
esac
