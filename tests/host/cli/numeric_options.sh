# Numeric options of seqslam and seqslam-sim: NaN, infinities, hexadecimal and values outside
# the option's range (or its value type: no silent wrap) are usage errors (status 2) that name
# the option and the range it takes, before anything is read or written. The range named is the
# one --help shows. Sizes "WxH" are read strictly by every tool (seqslam_tools/wxh.h).
# Usage: numeric_options.sh SEQSLAM_SIM SEQSLAM_DEMO
source "$(dirname "$0")/lib.sh"
SIM=${1:?seqslam-sim}
DEMO=${2:?seqslam-demo}
[[ -x $SIM ]] || die "$SIM not built (cmake --build ... --target seqslam-sim)"
[[ -x $DEMO ]] || die "$DEMO not built (cmake --build ... --target seqslam-demo)"

# refused VALUE RANGE CMD...: CMD (with VALUE somewhere) exits 2, stderr names the option
# (the first argument that starts with --, before VALUE) and RANGE, and no output exists.
refused() {
  local value=$1 range=$2
  shift 2
  local option="" a
  for a in "$@"; do
    [[ $a == "$value" ]] && break
    [[ $a == --* ]] && option=$a
  done
  rm -rf out
  expect 2 "" "$@"
  grep -Fq -- "$option: '$value' is not" err.txt && grep -Fq -- "$range" err.txt || {
    show
    die "'$*': the message does not name $option, '$value' and $range"
  }
  [[ ! -e out ]] || die "'$*' wrote out"
}

# help_shows CMD... -- OPTION RANGE: the option's --help line shows RANGE.
help_shows() {
  local option=$2 range=$3
  run "$1" $4 --help
  grep -E -- "^ +$option [A-Z]+:" out.txt | grep -Fq -- ":$range" || {
    show
    die "'$1 $4 --help' does not show $option as $range"
  }
}

bad_reals=(nan NaN inf -inf Infinity 1e999 0x1p1 "")

# --- seqslam slam: every floating option, and the integer ones that were narrowed.
slam_reals=(
  "--drift-base 0..1000" "--drift-rate 0..1" "--heading-base 0..180" "--heading-rate 0..10"
  "--near 0..1000" "--relocalise-turn 0..180" "--max-image-rank 0..1"
  "--closure-weight 0.001..1000" "--closure-heading-weight 0..1000" "--hfov 1..179"
  "--path-band 0.01..100"
)
for spec in "${slam_reals[@]}"; do
  read -r option range <<<"$spec"
  lo=${range%..*}
  hi=${range#*..}
  for v in "${bad_reals[@]}" "-$hi" "${hi}1"; do
    refused "$v" "$range" "$SEQSLAM" slam missing.dream --out out --json out "$option" "$v"
  done
  [[ $lo == 0 ]] && refused "-0.5" "$range" "$SEQSLAM" slam missing.dream --out out "$option" -0.5
  help_shows "$SEQSLAM" "$option" "$range" slam
done
for spec in "--seq-len 1..100 101" "--window 0..255 256" "--exclusion 0..65535 65536" \
  "--recent-exclusion 1..65535 0" "--confirm 1..1000 1001" "--budget 1..10000000 -1" \
  "--exclusion 0..65535 0x10" "--window 0..255 010"; do
  read -r option range v <<<"$spec"
  refused "$v" "$range" "$SEQSLAM" slam missing.dream --out out "$option" "$v"
done
help_shows "$SEQSLAM" --exclusion 0..65535 slam

# --- seqslam eval / run: the heuristic's and the slope search's settings, and the sizes.
for sub in eval run; do
  for spec in "--candidate-threshold 0..255" "--vmin 0.01..4" "--vmax 0.01..4"; do
    read -r option range <<<"$spec"
    for v in "${bad_reals[@]}" -1 300; do
      refused "$v" "$range" "$SEQSLAM" $sub lib qry --json out "$option" "$v"
    done
    help_shows "$SEQSLAM" "$option" "$range" $sub
  done
  for spec in "--seq-len 1..100 0" "--window 0..255 256" "--exclusion 0..65535 65536" \
    "--exclusion 0..65535 -1" "--k 1..16 17" "--vsteps 1..32 0" "--max-shift 0..255 256" \
    "--threads 0..4294967295 -1" "--route-window 0..65535 65536"; do
    read -r option range v <<<"$spec"
    refused "$v" "$range" "$SEQSLAM" $sub lib qry --json out "$option" "$v"
  done
done

# --- seqslam sweep: every value of a list is checked.
for spec in "--seq-len 1..100 30,101" "--window 0..255 50,256" "--exclusion 0..65535 10,65536" \
  "--max-shift 0..255 0,-1" "--threads 0..4294967295 -1"; do
  read -r option range v <<<"$spec"
  rm -f out
  expect 2 "" "$SEQSLAM" sweep --pair a,b,c --out out "$option" "$v"
  grep -Fq -- "$option: '${v#*,}' is not" err.txt && grep -Fq -- "$range" err.txt || {
    show
    die "sweep $option $v: the message does not name the value and $range"
  }
  [[ ! -e out ]] || die "sweep $option $v wrote out"
done
for v in nan inf 1.5 -0.1; do
  expect 2 "--threshold: '$v' is not" "$SEQSLAM" sweep --pair a,b,c --out out --threshold "$v"
  [[ ! -e out ]] || die "sweep --threshold $v wrote out"
done

# --- seqslam config write and results: decimals (nan and inf are not decimals).
ok "$SEQSLAM" disk create d.img --file config:1K
for option in --threshold --sigma-min --candidate-threshold --route-growth --spacing; do
  for v in nan inf -inf 0x10; do
    expect 2 "$option: '$v' is not a decimal number" "$SEQSLAM" config write d.img "$option" "$v"
  done
done
expect 1 "d.img:config: not a usable run configuration" "$SEQSLAM" config show d.img

# --- seqslam-sim: truth, generate, render, montage, drift, evaluate.
for spec in "--gate 0.001..1000" "--max-heading 0..180"; do
  read -r option range <<<"$spec"
  for v in "${bad_reals[@]}" -1 2000; do
    refused "$v" "$range" "$SIM" truth lib.dream qry.dream --out out "$option" "$v"
  done
  help_shows "$SIM" "$option" "$range" truth
done
refused 0 "0.001..1000" "$SIM" truth lib.dream qry.dream --out out --gate 0
refused -1 "0..4294967295" "$SIM" truth lib.dream qry.dream --out out --tolerance -1
for v in "${bad_reals[@]}" -0.1 1.5; do
  refused "$v" "0..1" "$SIM" generate --out out --deviation "$v"
done
refused -1 "0..18446744073709551615" "$SIM" generate --out out --seed -1
refused 18446744073709551616 "0..18446744073709551615" "$SIM" generate --out out --seed \
  18446744073709551616
for option in --x --y; do
  for v in nan inf -inf; do
    expect 2 "$option: '$v' is not a finite decimal number" "$SIM" render --out out/v "$option" "$v"
  done
done
refused nan "-360..360" "$SIM" render --out out/v --heading nan
refused 400 "-360..360" "$SIM" render --out out/v --heading 400
refused inf "-180..180" "$SIM" render --out out/v --roll inf
for v in nan:1:1 0:inf:1 0:1:nan 0:1:0; do
  expect 2 "--rotation: expected FROM:TO:STEP \(finite numbers" "$SIM" generate --out out \
    --scenario perspective --rotation "$v"
  [[ ! -e out ]] || die "generate --rotation $v wrote out"
done
expect 2 "--scale: expected FROM:TO:STEP \(finite numbers, FROM > 0" "$SIM" generate --out out \
  --scenario perspective --scale 0:1:0.5
refused -1 "0..4294967295" "$SIM" montage a.dream --out out --first -1
refused 0 "1..1000" "$SIM" drift --runs 0
refused 101 "1..100" "$SIM" evaluate dir --seq-len 101
refused 65536 "0..65535" "$SIM" evaluate dir --exclusion 65536

# --- WxH sizes: no trailing text, sign, space, fraction or overflow, in any tool (sscanf
# took "32x16junk" and wrapped "99999999999x16").
names() { grep -Fq -- "'$1'" err.txt || { show; die "the message does not name '$1'"; }; }
for v in 32x16junk +32x16 " 32x16" 3.5x2 99999999999x16 32x 0x16; do
  expect 2 "--size: '" "$DEMO" --size "$v"
  expect 2 "--size: expected WxH within 346x271, got" "$SIM" generate --out out --size "$v"
  names "$v"
  [[ ! -e out ]] || die "generate --size '$v' wrote out"
  rm -f cfg.img
  expect 2 "--size: " "$SEQSLAM" config write cfg.img --size "$v"
  names "$v"
  [[ ! -e cfg.img ]] || die "config write --size '$v' wrote cfg.img"
  expect 2 "--grid-size: .* is not WxH cells" "$SEQSLAM" config write cfg.img --grid-size "$v"
  names "$v"
  [[ ! -e cfg.img ]] || die "config write --grid-size '$v' wrote cfg.img"
done
echo PASS
