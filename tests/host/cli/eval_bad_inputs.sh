# Bad inputs to seqslam run / eval: each case exits with the documented status (1 bad input,
# 2 usage error), names the file (and line) or option on stderr, and prints no results on
# stdout and writes no output file. Usage: eval_bad_inputs.sh CASE
source "$(dirname "$0")/lib.sh"
REF="$DATA/corridor/ref"
QRY="$DATA/corridor/query"
GT="$DATA/corridor/ground_truth.csv"

# fails STATUS REGEX ARGS...: seqslam ARGS... exits with STATUS, stderr matches REGEX, and
# nothing was printed as a result (run prints its CSV on stdout) or written (eval is given
# --json result.json).
fails() {
  local want=$1 regex=$2
  shift 2
  rm -f result.json
  if [[ $1 == eval ]]; then
    expect "$want" "$regex" "$SEQSLAM" "$@" --json result.json
  else
    expect "$want" "$regex" "$SEQSLAM" "$@"
  fi
  [[ ! -s out.txt ]] || {
    show
    die "'seqslam $*' printed a result although it failed"
  }
  [[ ! -e result.json ]] || die "'seqslam $*' wrote result.json although it failed"
}

# A directory with the first N corridor library images.
some_images() {
  mkdir -p "$1"
  local i
  for ((i = 0; i < $2; i++)); do cp "$REF/$(printf %07d $i).jpg" "$1/"; done
}

case "${1:?case}" in
  corrupt_image)
    some_images dir 12
    printf 'garbage, not a PNG\n' >dir/x.png
    fails 1 "dir/x.png: not a supported image" run dir "$QRY"
    fails 1 "dir/x.png: not a supported image" run "$REF" dir
    fails 1 "dir/x.png: not a supported image" eval dir "$QRY" --ground-truth identity:2
    : >dir/x.png # empty
    fails 1 "dir/x.png" run dir "$QRY"
    head -c 200 "$REF/0000000.jpg" >dir/x.png # a JPEG cut short, under a PNG name
    fails 1 "dir/x.png" run dir "$QRY"
    ;;
  small_image)
    # Mixed sizes are fine: each image is reduced to the default 12x10.
    some_images mixed 12
    printf 'P5\n40 20\n255\n' >mixed/0000003b.pgm
    head -c 800 /dev/urandom >>mixed/0000003b.pgm
    ok "$SEQSLAM" run mixed mixed --seq-len 3
    [[ $(wc -l <out.txt) -eq 14 ]] || die "expected 13 rows for 13 images"
    # An image smaller than the target size cannot be reduced: named.
    printf 'P5\n16 8\n255\n' >mixed/0000004b.pgm
    head -c 128 /dev/zero >>mixed/0000004b.pgm
    fails 1 "mixed/0000004b.pgm: cannot reduce 16x8 to 12x10" run mixed "$QRY"
    fails 1 "mixed/0000004b.pgm: cannot reduce 16x8 to 32x16" eval "$REF" mixed \
      --ground-truth identity:1 --size 32x16
    # ... fine for a smaller target.
    ok "$SEQSLAM" run mixed mixed --size 16x8 --seq-len 3
    ;;
  empty_dir)
    mkdir empty
    fails 1 "empty: directory contains no images" run empty "$QRY"
    fails 1 "empty: directory contains no images" run "$REF" empty
    echo notes >empty/readme.txt
    fails 1 "empty: directory contains no images" eval empty "$QRY" --ground-truth identity:2
    ;;
  index_missing)
    printf '%s\n# a comment\nnope.jpg\n' "$REF/0000000.jpg" >idx.txt
    fails 1 "idx.txt:3: listed image 'nope.jpg' does not exist" run idx.txt "$QRY"
    fails 1 "idx.txt:3: listed image 'nope.jpg' does not exist" run "$REF" idx.txt
    : >empty.txt
    fails 1 "empty.txt" run empty.txt "$QRY"
    fails 1 "nosuch: no such file or directory" run nosuch "$QRY"
    fails 1 "nosuch: no such file or directory" run "$REF" nosuch
    ;;
  ground_truth)
    some_images lib 41
    # The corridor's CSV names library images beyond these 41 (and queries beyond 41).
    fails 1 "ground_truth.csv: query [0-9]+ names library image 41 but lib has 41" \
      eval lib "$QRY" --ground-truth "$GT"
    fails 1 "ground_truth.csv: names query 110 but lib has 41 images" \
      eval "$REF" lib --ground-truth "$GT"
    printf 'query_index,matching_reference_indices\n0,1 2\n1,x\n' >bad.csv
    fails 1 "bad.csv:3:" eval "$REF" "$QRY" --ground-truth bad.csv
    fails 1 "nosuch.csv: no such file" eval "$REF" "$QRY" --ground-truth nosuch.csv
    fails 1 "has no true poses" eval "$REF" "$QRY" --ground-truth poses:1
    fails 1 "ground truth 'identity:x'" eval "$REF" "$QRY" --ground-truth identity:x
    fails 1 "ground truth 'poses:0'" eval "$REF" "$QRY" --ground-truth poses:0
    expect 2 "--ground-truth is required" "$SEQSLAM" eval "$REF" "$QRY"
    # Ranged inputs are judged by source index: the CSV fits the whole recordings.
    ok "$SEQSLAM" eval "$REF" "$QRY" --ground-truth "$GT" --query-range 50:80 --seq-len 5
    out_has "^26 queries with a full sequence \(the recall denominator\)$"
    ;;
  bad_flags)
    fails 2 "--size: '0x3': width and height must be at least 1 pixel" run "$REF" "$QRY" --size 0x3
    fails 2 "--size: '64x32' has 2048 pixels" run "$REF" "$QRY" --size 64x32
    fails 2 "--seq-len: '0' is not within 1..100" run "$REF" "$QRY" --seq-len 0
    fails 2 "--seq-len: '101' is not within 1..100" eval "$REF" "$QRY" --ground-truth identity:2 \
      --seq-len 101
    fails 2 "--seq-len" run "$REF" "$QRY" --seq-len 70000
    fails 2 "--threshold: '2' is not within 0..1" run "$REF" "$QRY" --threshold 2
    fails 2 "--threshold" run "$REF" "$QRY" --threshold abc
    fails 2 "--library-range: range '9:3': LAST must be above FIRST" \
      run "$REF" "$QRY" --library-range 9:3
    fails 2 "--query-range: range 'x:1': 'x' is not an index" run "$REF" "$QRY" --query-range x:1
    fails 2 "--query-range: range '4'" run "$REF" "$QRY" --query-range 4
    fails 2 "window must be 0 \(off\) or 2..255" run "$REF" "$QRY" --window 1
    fails 2 "max_shift must be smaller than the image width" run "$REF" "$QRY" --max-shift 32
    fails 2 "--max-shift" run "$REF" "$QRY" --max-shift 300
    fails 2 "--preprocess: 'foo' is not one of" run "$REF" "$QRY" --preprocess foo
    fails 2 "--matcher: 'other' is not one of diagonal, heuristic, slope" run "$REF" "$QRY" --matcher other
    fails 2 "--threads" run "$REF" "$QRY" --threads -1
    fails 2 "query is required" run "$REF"
    # A range that parses but does not fit the data is a bad input (1), named.
    fails 1 "query: range 100:200 does not fit its 111 images" run "$REF" "$QRY" --query-range 100:200
    fails 1 "ref: range 111: does not fit its 111 images" run "$REF" "$QRY" --library-range 111:
    # Upscaling is refused at the first image.
    fails 1 "cannot reduce 160x120 to 200x2" run "$REF" "$QRY" --size 200x2
    ;;
  truncated_dream)
    ok "$SEQSLAM" convert images-to-dream "$REF" ref.dream --size 32x16
    ok "$SEQSLAM" convert images-to-dream "$QRY" query.dream --size 32x16
    head -c 30000 ref.dream >cut.dream
    fails 1 "cut.dream" run cut.dream query.dream
    fails 1 "cut.dream" eval query.dream cut.dream --ground-truth "$GT"
    # Cut at a block boundary inside a record: the places before it are not taken as all.
    head -c 30208 ref.dream >cut_block.dream
    fails 1 "cut_block.dream: damaged or invalid record after place [0-9]+ \(the log ends before its committed end" \
      run cut_block.dream query.dream
    head -c 300 ref.dream >header_cut.dream
    fails 1 "header_cut.dream" run header_cut.dream query.dream
    # Recordings of another size: without --size the library's size is taken, and a query of
    # another size is refused naming it; an explicit --size that is not the recording's is
    # refused saying which to use.
    ok "$SEQSLAM" convert images-to-dream "$REF" small.dream --size 16x8
    ok "$SEQSLAM" convert images-to-dream "$QRY" small_query.dream --size 16x8
    fails 1 "query.dream: recorded at 32x16 .*use --size 32x16" run small.dream query.dream
    fails 1 "small.dream: recorded at 16x8 .*use --size 16x8" run small.dream query.dream --size 32x16
    ok "$SEQSLAM" eval small.dream small_query.dream --ground-truth "$GT"
    grep -q "^library small.dream: 111 images; query small_query.dream: 111 images; 16x8 he-pn," \
      out.txt || die "eval without --size did not take the recordings' 16x8: $(head -1 out.txt)"
    ;;
  *)
    die "unknown case $1"
    ;;
esac
echo PASS
