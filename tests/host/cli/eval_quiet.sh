# seqslam eval --quiet prints nothing on stdout but what was asked for (--json -), with and
# without --reference (whose comparison then goes only into the JSON).
source "$(dirname "$0")/lib.sh"
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 32x16
ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/query" query.dream --size 32x16

ok "$SEQSLAM" eval ref.dream query.dream --ground-truth identity:2 --quiet --json -
python3 -c 'import json,sys; json.load(open(sys.argv[1]))' out.txt || die "--quiet --json -: not JSON"
ok "$SEQSLAM" eval ref.dream query.dream --ground-truth identity:2 --reference
out_has "^reference \(double precision, direct sums\): same best place on 82 of 82 queries"
ok "$SEQSLAM" eval ref.dream query.dream --ground-truth identity:2 --reference --quiet
[[ ! -s out.txt ]] || {
  show
  die "eval --quiet --reference printed on stdout"
}
echo PASS
