# Bad inputs: each case exits with the documented status (1 runtime failure, 2 usage error)
# and says on stderr what is wrong with which file or option. Usage: bad_inputs.sh CASE
source "$(dirname "$0")/lib.sh"
REF="$DATA/corridor/ref"

case "${1:?case}" in
  missing_file)
    expect 1 "nosuch.img: cannot open disk image: No such file" "$SEQSLAM" disk list nosuch.img
    expect 1 "nosuch.dream: no such file" "$SEQSLAM" dream info nosuch.dream
    expect 1 "nosuch.img: no such file \(in 'nosuch.img:replay'\)" \
      "$SEQSLAM" convert dream-to-images nosuch.img:replay out
    expect 1 "nosuch.img: no such file" "$SEQSLAM" results nosuch.img
    expect 1 "nosuch.img: cannot open disk image" "$SEQSLAM" config show nosuch.img
    expect 1 "nosuch: no such file or directory" \
      "$SEQSLAM" convert images-to-dream nosuch out.dream --size 32x16
    ok "$SEQSLAM" disk create disk.img --file a:1K
    expect 1 "nosuch.bin: no such file" "$SEQSLAM" disk import disk.img a nosuch.bin
    expect 1 "nosuch.bin: no such file" "$SEQSLAM" disk create d2.img --file a:1K:nosuch.bin
    # A symbolic link loop and a dangling link say so (issue 34: "no such file").
    ln -s loop_b loop_a
    ln -s loop_a loop_b
    ln -s gone.dream dangling.dream
    loop="a symbolic link loop \(Too many levels of symbolic links\)"
    expect 1 "^seqslam: error: loop_a: $loop$" "$SEQSLAM" dream info loop_a
    expect 1 "^seqslam: error: loop_a: $loop \(in 'loop_a:replay'\)$" "$SEQSLAM" results loop_a:replay
    expect 1 "^seqslam: error: dangling.dream: a dangling symbolic link \(to gone.dream, which does not exist\)$" \
      "$SEQSLAM" dream info dangling.dream
    expect 1 "^seqslam: error: loop_a: $loop$" "$SEQSLAM" disk import disk.img a loop_a
    expect 1 "^seqslam: error: loop_a: $loop$" "$SEQSLAM" disk create d2.img --file a::loop_a
    expect 1 "^seqslam: error: loop_a: $loop$" "$SEQSLAM" convert images-to-dream loop_a x.dream \
      --size 32x16
    expect 1 "^seqslam: error: loop_a: $loop$" "$SEQSLAM" sweep --pairs loop_a --out s.csv
    expect 1 "^seqslam: error: dangling.dream: a dangling symbolic link" "$SEQSLAM" tune dangling.dream
    # Not a regular file: refused by every reader, never read until it ends.
    expect 1 "^seqslam: error: /dev/zero: is not a regular file" "$SEQSLAM" sweep --pairs /dev/zero \
      --out s.csv
    expect 1 "^seqslam: error: /dev/zero: is not a regular file" "$SEQSLAM" disk import disk.img a \
      /dev/zero
    ;;
  not_whole_blocks)
    head -c 1000 /dev/zero >odd.img
    expect 1 "odd.img: a disk image must be a non-zero whole number of 512-byte blocks \(it has 1000 bytes\)" \
      "$SEQSLAM" disk list odd.img
    : >empty.img
    expect 1 "empty.img: a disk image must be a non-zero whole number" "$SEQSLAM" disk list empty.img
    ;;
  no_volume)
    head -c 4096 /dev/zero >zero.img
    expect 1 "zero.img: cannot mount the volume: block 0 is not a seqslam volume \(magic SQSLVOL1 missing\)" \
      "$SEQSLAM" disk list zero.img
    ok "$SEQSLAM" disk create disk.img --file config:1K
    flip_byte disk.img 20 # inside the file table: checksum mismatch
    expect 1 "disk.img: cannot mount the volume: the file table \(block 0\) is damaged: checksum mismatch" \
      "$SEQSLAM" config show disk.img
    ;;
  wrong_magic_in_file)
    ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 8x4
    seq 1 300 >text.bin
    ok "$SEQSLAM" disk create disk.img --file config::ref.dream --file record::text.bin
    expect 1 "disk.img:record: not a readable dream recording: not a log of the expected kind \(wrong magic in block 0\)" \
      "$SEQSLAM" dream info disk.img:record
    expect 1 "disk.img:config: not a usable run configuration: not a log of the expected kind" \
      "$SEQSLAM" config show disk.img
    expect 1 "text.bin: not a readable dream recording: not a log of the expected kind" \
      "$SEQSLAM" convert dream-to-images text.bin out
    ;;
  truncated_dream)
    ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
    head -c 30000 ref.dream >cut.dream
    expect 1 "cut.dream: the file is truncated \(30000 bytes, not a whole number of 512-byte blocks\)" \
      "$SEQSLAM" dream info cut.dream
    # The log committed 111 places: the cut is reported as lost records, not as a power cut.
    out_has "log end +cut short or damaged at byte" "places +51$" "records lost +60$"
    err_has "cut.dream: record skipped: the log ends before its committed end"
    expect 1 "cut.dream: the file is truncated" "$SEQSLAM" convert dream-to-images cut.dream out
    [[ $(ls out | wc -l) -eq 51 ]] || die "the 51 places before the cut should be written"
    head -c 300 ref.dream >header_cut.dream
    expect 1 "header_cut.dream: not a readable dream recording: the header block is damaged" \
      "$SEQSLAM" dream info header_cut.dream
    ;;
  oversized_image_size)
    expect 2 "--size: '64x32' has 2048 pixels; the FPGA pixel buffer holds at most 512" \
      "$SEQSLAM" convert images-to-dream "$REF" out.dream --size 64x32
    [[ ! -e out.dream ]] || die "out.dream should not be created"
    ok "$SEQSLAM" disk create disk.img --file config:1K
    expect 2 "--size: '23x23' has 529 pixels" "$SEQSLAM" config write disk.img --size 23x23
    expect 2 "--size: '32by16' is not an image size WxH" \
      "$SEQSLAM" convert images-to-dream "$REF" out.dream --size 32by16
    ;;
  oversized_disk_size)
    expect 2 "a disk image holds at most 4294967295 blocks \(2 TiB\)" \
      "$SEQSLAM" disk create big.img --size 3000G --file a:1K
    [[ ! -e big.img ]] || die "big.img should not be created"
    expect 2 "--size: '3T' has an unknown suffix" "$SEQSLAM" disk create big.img --size 3T --file a:1K
    expect 2 "--size: '99999999999999999999' is too large" \
      "$SEQSLAM" disk create big.img --size 99999999999999999999 --file a:1K
    ;;
  disk_size_too_small)
    expect 2 "--size 10K gives 20 blocks = 10240 bytes, but the file table and the files need 201 blocks" \
      "$SEQSLAM" disk create small.img --size 10K --file a:100K
    [[ ! -e small.img ]] || die "small.img should not be created"
    ;;
  unknown_preprocess)
    ok "$SEQSLAM" disk create disk.img --file config:1K
    expect 2 "--preprocess: 'foo' is not one of none, he, pn, igk, he-pn, igk-pn, igk-he" \
      "$SEQSLAM" config write disk.img --preprocess foo
    expect 2 "--modes: 'fly' is not one of teach" "$SEQSLAM" config write disk.img --modes teach,fly
    expect 2 "--trigger: 'sometimes' is not one of distance, every-frame" "$SEQSLAM" config write disk.img --trigger sometimes
    # The firmware runs the diagonal or the heuristic matcher (slope search is host-only).
    expect 2 "invalid configuration for the firmware: matcher slope: the firmware has no slope matcher" \
      "$SEQSLAM" config write disk.img --matcher slope
    ;;
  invalid_config)
    ok "$SEQSLAM" disk create disk.img --file config:1K
    expect 2 "--seq-len: '500' is not within 1..100" "$SEQSLAM" config write disk.img --seq-len 500
    expect 2 "invalid configuration: sequence.window must be 0 \(off\) or 2..255" \
      "$SEQSLAM" config write disk.img --window 1
    expect 2 "invalid configuration: max_shift must be smaller than the image width" \
      "$SEQSLAM" config write disk.img --size 8x4 --max-shift 8
    expect 2 "invalid configuration: sequence.sigma_min must be > 0" \
      "$SEQSLAM" config write disk.img --sigma-min 0
    expect 2 "--recent-exclusion: '0' is not within 1..65535" \
      "$SEQSLAM" config write disk.img --recent-exclusion 0
    expect 2 "--threshold: '1.5' is not within 0..1" "$SEQSLAM" config write disk.img --threshold 1.5
    expect 2 "--spacing: '-1' is not above 0 and at most 1000 m" \
      "$SEQSLAM" config write disk.img --spacing -1
    expect 2 "--seq-len" "$SEQSLAM" config write disk.img --seq-len 70000
    # The heuristic's settings: the ranges of seqslam eval.
    expect 2 "--k: '0' is not within 1..16" "$SEQSLAM" config write disk.img --k 0
    expect 2 "--k: '17' is not within 1..16" "$SEQSLAM" config write disk.img --k 17
    expect 2 "--guard: '0' is not within 1..65535" "$SEQSLAM" config write disk.img --guard 0
    expect 2 "--candidate-threshold: '300' is not within 0..255 grey levels per pixel" \
      "$SEQSLAM" config write disk.img --matcher heuristic --candidate-threshold 300
    expect 2 "--candidate-threshold: '-1' is not within 0..255" \
      "$SEQSLAM" config write disk.img --candidate-threshold -1
    expect 2 "--heuristic-scan-places: '65536' is not within 0..65535" \
      "$SEQSLAM" config write disk.img --heuristic-scan-places 65536
    expect 2 "--heuristic-scan-places: '-1' is not within 0..65535" \
      "$SEQSLAM" config write disk.img --heuristic-scan-places -1
    # Nothing was written.
    expect 1 "disk.img:config: not a usable run configuration" "$SEQSLAM" config show disk.img
    ;;
  from_does_not_fit)
    head -c 3000 /dev/zero >big.bin
    expect 1 "big.bin \(3000 bytes\) does not fit in volume file 'a' \(2 blocks = 1024 bytes\)" \
      "$SEQSLAM" disk create d.img --file a:1K:big.bin
    [[ ! -e d.img ]] || die "d.img should not be created"
    ;;
  import_does_not_fit)
    ok "$SEQSLAM" disk create d.img --file a:1K --file b:1K
    head -c 1025 /dev/zero >big.bin
    expect 1 "big.bin \(1025 bytes\) does not fit in volume file 'a' of d.img \(2 blocks = 1024 bytes\)" \
      "$SEQSLAM" disk import d.img a big.bin
    ;;
  missing_volume_file)
    ok "$SEQSLAM" disk create d.img --file a:1K --file b:1K
    expect 1 "d.img: no volume file 'config' \(the volume has: a, b\)" "$SEQSLAM" config show d.img
    expect 1 "d.img: no volume file 'config'" "$SEQSLAM" config write d.img
    expect 1 "d.img: no volume file 'results'" "$SEQSLAM" results d.img
    expect 1 "d.img: no volume file 'zz'" "$SEQSLAM" disk export d.img zz out.bin
    expect 1 "d.img: no volume file 'zz'" "$SEQSLAM" dream info d.img:zz
    ;;
  full_variant)
    expect 2 "--variant full: a full recording needs sensor snapshots and odometry" \
      "$SEQSLAM" convert images-to-dream "$REF" out.dream --size 32x16 --variant full
    expect 2 "--variant: half not in" \
      "$SEQSLAM" convert images-to-dream "$REF" out.dream --size 32x16 --variant half
    ;;
  bad_file_spec)
    expect 2 "--file: 'bad name' is not a valid volume file name" \
      "$SEQSLAM" disk create d.img --file 'bad name:1K'
    expect 2 "'sixteen-chars-xx' is not a valid volume file name" \
      "$SEQSLAM" disk create d.img --file sixteen-chars-xx:1K
    expect 2 "--file: 'a' is not NAME:SIZE\[:FROM\]" "$SEQSLAM" disk create d.img --file a
    expect 2 "SIZE is missing" "$SEQSLAM" disk create d.img --file a:
    expect 2 "SIZE must be at least 1 byte" "$SEQSLAM" disk create d.img --file a:0
    expect 2 "volume file 'a' is given twice" "$SEQSLAM" disk create d.img --file a:1K --file a:2K
    expect 2 "at most 15 files" "$SEQSLAM" disk create d.img \
      $(for i in $(seq 1 16); do echo --file f$i:1K; done)
    [[ ! -e d.img ]] || die "d.img should not be created"
    ;;
  ground_truth_file)
    "$CLI_FIXTURES" results results.bin 12 expected.csv # captures 5..16
    ok "$SEQSLAM" disk create disk.img --file config:1K --file results::results.bin
    ok "$SEQSLAM" config write disk.img
    expect 1 "^seqslam: error: nosuch.csv: no such file$" \
      "$SEQSLAM" results disk.img --ground-truth nosuch.csv
    printf 'query_index,matching_reference_indices\n0,1 2\nx,3\n' >bad_line.csv
    expect 1 "^seqslam: error: bad_line.csv:3: query index 'x' is not a non-negative decimal integer$" \
      "$SEQSLAM" results disk.img --ground-truth bad_line.csv
    printf '0,1\n1,2\n' >no_header.csv
    expect 1 "^seqslam: error: no_header.csv:1: bad header '0,1'" \
      "$SEQSLAM" results disk.img --ground-truth no_header.csv
    printf 'query_index,matching_reference_indices\n5,1,2\n' >fields.csv
    expect 1 "^seqslam: error: fields.csv:2: expected 2 comma-separated fields" \
      "$SEQSLAM" results results.bin --ground-truth fields.csv
    [[ ! -s out.txt ]] || die "nothing is printed for a bad ground truth"
    # Queries beyond the last capture (16): the ground truth of another run.
    printf 'query_index,matching_reference_indices\n17,1\n' >other_run.csv
    expect 1 "^seqslam: error: other_run.csv: the ground truth has queries up to 17, but the results in disk.img:results end at capture 16" \
      "$SEQSLAM" results disk.img --ground-truth other_run.csv
    # The threshold the firmware used cannot be known from a damaged configuration.
    printf 'query_index,matching_reference_indices\n5,0\n' >gt.csv
    flip_byte disk.img $((512 + 40))
    expect 1 "^seqslam: error: disk.img:config: not a usable run configuration \(.*\), so the threshold the firmware used is unknown: give --threshold$" \
      "$SEQSLAM" results disk.img --ground-truth gt.csv
    ok "$SEQSLAM" results disk.img --ground-truth gt.csv --threshold 0.85
    ;;
  results_options)
    "$CLI_FIXTURES" results results.bin 12 expected.csv
    printf 'query_index,matching_reference_indices\n5,0\n' >gt.csv
    expect 2 "--threshold: '1.5' is not within 0..1" \
      "$SEQSLAM" results results.bin --ground-truth gt.csv --threshold 1.5
    expect 2 "--threshold: 'high' is not a decimal number" \
      "$SEQSLAM" results results.bin --ground-truth gt.csv --threshold high
    expect 2 "--threshold: '-0.1' is not within 0..1" \
      "$SEQSLAM" results results.bin --ground-truth gt.csv --threshold -0.1
    expect 2 "--threshold requires --ground-truth" "$SEQSLAM" results results.bin --threshold 0.5
    expect 2 "--json requires --ground-truth" "$SEQSLAM" results results.bin --json s.json
    [[ ! -e s.json ]] || die "s.json should not be created"
    expect 2 "--csv -: with --ground-truth the summary goes to standard output" \
      "$SEQSLAM" results results.bin --ground-truth gt.csv --csv -
    expect 2 "--ground-truth" "$SEQSLAM" results results.bin --ground-truth
    ;;
  route_options)
    # The route search's settings: what the core refuses (check_localiser_config) with its
    # own sentence, what cannot be stored with the option's message; all status 2, and
    # nothing written.
    ok "$SEQSLAM" disk create disk.img --file config:1K
    window="invalid configuration: route.window must be odd, at least 2 \* exclusion \+ 3"
    expect 2 "$window" "$SEQSLAM" config write disk.img --route-window 32
    expect 2 "$window" "$SEQSLAM" config write disk.img --route-window 0
    # Too narrow for R (the firmware's run check: the route search runs in repeat mode).
    narrow="route.window must be at least 2 \* sequence.exclusion \+ 3 \(the route search\)"
    expect 2 "$narrow" "$SEQSLAM" config write disk.img --route-window 21 # R = 10: at least 23
    expect 2 "$narrow" "$SEQSLAM" config write disk.img --route-window 19 --exclusion 9
    expect 2 "--route-window: '65536' is not within 0..65535" \
      "$SEQSLAM" config write disk.img --route-window 65536
    expect 2 "--route-slack: '-1' is not within 0..65535" \
      "$SEQSLAM" config write disk.img --route-slack -1
    expect 2 "--lost-after: '0' is not within 1..65535" "$SEQSLAM" config write disk.img --lost-after 0
    expect 2 "--scan-places: '0' is not within 1..65535" \
      "$SEQSLAM" config write disk.img --scan-places 0
    expect 2 "--scan-seq-len: '0' is not within 1..65535" \
      "$SEQSLAM" config write disk.img --scan-seq-len 0
    expect 2 "--scan-seq-len: '70000' is not within 1..65535" \
      "$SEQSLAM" config write disk.img --scan-seq-len 70000
    expect 2 "--start: '-2' is not a library place \(a whole number within 0..2147483647\) or 'unknown'" \
      "$SEQSLAM" config write disk.img --start -2
    expect 2 "--start: 'somewhere' is not a library place" \
      "$SEQSLAM" config write disk.img --start somewhere
    expect 2 "--start: '1.5' is not a library place" "$SEQSLAM" config write disk.img --start 1.5
    expect 2 "--start: 'Unknown' is not a library place" \
      "$SEQSLAM" config write disk.img --start Unknown
    expect 2 "--start: '2147483648' is not a library place \(a whole number within 0..2147483647\)" \
      "$SEQSLAM" config write disk.img --start 2147483648
    # Growth: a decimal stored as UQ8.8 (steps of 1/256, up to 255.996).
    range="is not within 0..255.996 places per place \(UQ8.8, steps of 1/256\)"
    expect 2 "--route-growth: '-0.05' $range" "$SEQSLAM" config write disk.img --route-growth -0.05
    expect 2 "--route-growth: '256' $range" "$SEQSLAM" config write disk.img --route-growth 256
    expect 2 "--route-growth: '255.9981' $range" \
      "$SEQSLAM" config write disk.img --route-growth 255.9981
    expect 2 "--route-growth: '0.001' is below half the smallest step of UQ8.8 \(1/256 = 0.00390625\) and would be stored as 0" \
      "$SEQSLAM" config write disk.img --route-growth 0.001
    for v in nan NaN inf -inf 1e-2 0x10 5% "" .; do
      expect 2 "--route-growth: '$v' is not a decimal number" \
        "$SEQSLAM" config write disk.img --route-growth "$v"
    done
    expect 2 "--route-growth: '0.0000000000000000001' has too many digits" \
      "$SEQSLAM" config write disk.img --route-growth 0.0000000000000000001
    # Nothing was written.
    expect 1 "disk.img:config: not a usable run configuration" "$SEQSLAM" config show disk.img
    ;;
  commit_slot)
    # A zeroed commit slot (issue 34: neither used nor reported): the log is read with the
    # other slot, and the damage is reported, status 1; both zeroed: the end is unknown and
    # no count of lost records is made up (it counted 2^32 - 12).
    "$CLI_FIXTURES" results res.bin 12 res.csv
    ok "$SEQSLAM" results res.bin
    for slot in 1 2; do
      cp res.bin "slot$slot.bin"
      dd if=/dev/zero of="slot$slot.bin" bs=512 seek="$slot" count=1 conv=notrunc status=none
      expect 1 "^seqslam: warning: slot$slot.bin: a commit slot is damaged \(zeros or another session's\): where the log ends is known only from the other slot, one commit older \(slot $slot\)$" \
        "$SEQSLAM" results "slot$slot.bin"
      out_has "^12 results \(.*\), 0 damaged records; the log ends cleanly$"
    done
    ok "$SEQSLAM" disk create d.img --file results::slot2.bin --file queries:4K
    ok "$SEQSLAM" disk list d.img
    out_has "^results .* results: session [0-9]+, 12 results, ends cleanly, commit slot 2 damaged \(zeros or another session's\)$" \
      "^queries .* empty \(zeros\)$"
    ok "$SEQSLAM" disk import d.img queries res.csv
    ok "$SEQSLAM" disk list d.img
    out_has "^queries .* query history \(scratch, no header\)$"
    cp res.bin both.bin
    dd if=/dev/zero of=both.bin bs=512 seek=1 count=2 conv=notrunc status=none
    expect 1 "both.bin: the log ends before its committed end, or its commit slots are damaged: .*: how many results it held is unknown$" \
      "$SEQSLAM" results both.bin
    ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 16x8
    dd if=/dev/zero of=ref.dream bs=512 seek=2 count=1 conv=notrunc status=none
    expect 1 "^seqslam: warning: ref.dream: a commit slot is damaged .* \(slot 2\)$" \
      "$SEQSLAM" dream info ref.dream
    out_has "places +111$"
    ;;
  *)
    die "unknown case $1"
    ;;
esac
echo PASS
