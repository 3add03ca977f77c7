# Outputs never destroy inputs and never report success when the write failed (issue 17;
# tools/common output_file.h). Usage: outputs.sh CASE SEQSLAM_SIM SEQSLAM_DEMO
#   input_is_output  an output that is an input: status 2 naming it, the input byte-identical
#   full_stdout      standard output on /dev/full: status 1, "writing standard output: ..."
#   full_file        /dev/full as the output file: status 1 naming it, no "done"
#   too_large        a regular file that cannot grow (ulimit -f, SIGXFSZ ignored): status 1,
#                    the old file untouched, no temporary left, the real row count
#   size_limit       every writer under `ulimit -f` with SIGXFSZ at its default action (as a
#                    shell has it; issue 34): status 1 naming the file, "File too large", the
#                    old file untouched, no temporary left
#   devices_kept     a FIFO or a device node given as IMAGE is never removed; a FIFO as a CSV
#                    output is written in place
#   interrupted      disk create killed by SIGTERM leaves no file and the old IMAGE as it was
#   sparse           disk create --size 2047G is quick and sparse, and the image lists
#   montage          seqslam-sim montage --count 4294967295: clamped, or a clean error
# (A regular file on a really full disk would need a small tmpfs, which a test cannot mount
# unprivileged; `ulimit -f` gives the same failed writes with EFBIG.)
source "$(dirname "$0")/lib.sh"
CASE=$1
SIM=$2
DEMO=$3
GT="$DATA/corridor/ground_truth.csv"

# No temporary output file (.NAME.tmp-XXXXXX) may be left in the directory.
no_temporaries() {
  local left
  left=$(find . -maxdepth 1 -name '.*.tmp-*' | head -n 5)
  [[ -z $left ]] || die "temporaries left behind: $left"
}

# expect_full STATUS REGEX CMD...: like expect, with standard output on /dev/full.
expect_full() {
  local want=$1 regex=$2
  shift 2
  set +e
  "$@" >/dev/full 2>err.txt
  status=$?
  set -e
  : >out.txt
  if [[ $status -ne $want ]] || ! grep -Eq -- "$regex" err.txt; then
    show
    die "'$* > /dev/full' exited with $status (expected $want) or stderr does not match /$regex/"
  fi
}

# Inputs: two recordings, a results file in a disk image, a directory of images.
make_inputs() {
  ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 32x16
  ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/query" query.dream --size 32x16
  "$CLI_FIXTURES" results res.bin 12 res.csv
  ok "$SEQSLAM" disk create r.img --file results::res.bin --file replay::ref.dream
  mkdir imgs
  cp "$DATA"/corridor/ref/000000[0-4].* imgs/
  cp "$GT" gt.csv
  for f in ref.dream query.dream r.img gt.csv; do cp "$f" "$f.orig"; done
}

# refused CMD...: status 2 with "FILE: is also an input", and every input as it was.
refused() {
  expect 2 "is also an input of this command" "$@"
  local f
  for f in ref.dream query.dream r.img gt.csv; do same "$f.orig" "$f"; done
}

case $CASE in
input_is_output)
  make_inputs
  refused "$SEQSLAM" results r.img --csv r.img
  err_has "^seqslam: error: r.img: is also an input of this command; refusing to overwrite it"
  refused "$SEQSLAM" results r.img:results --csv ./r.img
  ln r.img hard.img
  ln -s r.img soft.img
  refused "$SEQSLAM" results r.img --csv hard.img
  err_has "hard.img: is also an input of this command \(r.img\)"
  refused "$SEQSLAM" results soft.img --csv r.img
  refused "$SEQSLAM" results r.img --ground-truth gt.csv --json gt.csv
  refused "$SEQSLAM" disk export r.img replay r.img
  refused "$SEQSLAM" disk import r.img replay r.img
  refused "$SEQSLAM" disk create r.img --file replay::r.img
  first=$(ls imgs | head -n 1)
  cp "imgs/$first" first.orig
  refused "$SEQSLAM" convert images-to-dream imgs "imgs/$first" --size 32x16
  err_has "imgs/$first: is also an input"
  same first.orig "imgs/$first"
  refused "$SEQSLAM" convert dream-to-images ref.dream pngs --index ref.dream
  [[ ! -e pngs ]] || die "dream-to-images created its OUTDIR before refusing"
  refused "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --json ref.dream --quiet
  refused "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --json ./gt.csv --quiet
  refused "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --report query.dream
  refused "$SEQSLAM" run ref.dream query.dream --csv query.dream
  refused "$SEQSLAM" report ref.dream query.dream --ground-truth gt.csv --out ref.dream
  refused "$SEQSLAM" sweep --pair ref.dream,query.dream,gt.csv --out gt.csv
  refused "$SIM" montage ref.dream query.dream --out query.dream
  refused "$SIM" truth ref.dream query.dream --out ref.dream
  no_temporaries
  ;;

full_stdout)
  make_inputs
  if [[ ! -c /dev/full ]]; then
    echo "SKIP: no /dev/full"
    exit 0
  fi
  msg="writing standard output: No space left on device"
  expect_full 1 "$msg" "$SEQSLAM" disk list r.img
  expect_full 1 "$msg" "$SEQSLAM" dream info ref.dream
  expect_full 1 "$msg" "$SEQSLAM" results r.img
  expect_full 1 "standard output: write failed: No space left on device" \
    "$SEQSLAM" results r.img --csv -
  expect_full 1 "standard output: write failed: No space left on device" \
    "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --json - --quiet
  expect_full 1 "standard output: write failed: No space left on device" \
    "$SEQSLAM" run ref.dream query.dream
  expect_full 1 "$msg" "$SEQSLAM" explain PL10
  expect_full 1 "$msg" "$SEQSLAM" disk create new.img --file a:1K
  expect_full 1 "seqslam-sim: $msg" "$SIM" lights
  expect_full 1 "seqslam-demo: $msg" "$DEMO" --data "$DATA/corridor" --quiet
  # The same commands succeed on a working standard output.
  ok "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --json - --quiet
  ok "$SEQSLAM" results r.img --csv -
  ;;

full_file)
  make_inputs
  if [[ ! -c /dev/full ]]; then
    echo "SKIP: no /dev/full"
    exit 0
  fi
  full="/dev/full: write failed: No space left on device"
  expect 1 "^seqslam: error: $full$" "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv \
    --json /dev/full --quiet
  expect 1 "^seqslam: error: $full" "$SEQSLAM" results r.img --csv /dev/full
  printf 'query_index,matching_reference_indices\n0,0\n' >gt_small.csv
  expect 1 "^seqslam: error: $full" "$SEQSLAM" results r.img --ground-truth gt_small.csv \
    --threshold 0.5 --json /dev/full
  expect 1 "^seqslam: error: $full" "$SEQSLAM" disk export r.img replay /dev/full
  expect 1 "^seqslam: error: $full" "$SEQSLAM" convert dream-to-images ref.dream pngs \
    --index /dev/full
  expect 1 "^seqslam: error: /dev/full: cannot write disk image: No space left on device$" \
    "$SEQSLAM" disk create /dev/full --file a:1K
  [[ -c /dev/full ]] || die "/dev/full was removed"
  expect 1 "^seqslam: error: $full" "$SEQSLAM" sweep --pair ref.dream,query.dream,gt.csv \
    --seq-len 10,20 --out /dev/full
  if grep -q "done" out.txt; then
    show
    die "sweep to a full disk says done"
  fi
  expect 1 "^seqslam-sim: $full" "$SIM" montage ref.dream --count 4 --out /dev/full
  no_temporaries
  ;;

too_large)
  make_inputs
  # Files can grow to 1 block of 1024 bytes (bash's ulimit -f); a write beyond fails with
  # EFBIG ("File too large") as SIGXFSZ is ignored, as a full disk fails with ENOSPC.
  limited() { (trap '' XFSZ && ulimit -f 1 && exec "$@"); }
  printf '{"old": true}\n' >e.json
  cp e.json e.orig
  expect 1 "^seqslam: error: e.json: write failed: File too large$" limited "$SEQSLAM" eval \
    ref.dream query.dream --ground-truth gt.csv --json e.json --quiet
  same e.orig e.json
  expect 1 "^seqslam: error: out.csv: write failed: File too large" \
    limited "$SEQSLAM" results r.img --csv out.csv
  [[ ! -e out.csv ]] || die "a failed --csv left out.csv"
  expect 1 "^seqslam: error: big.img: cannot size disk image: File too large$" \
    limited "$SEQSLAM" disk create big.img --size 1M --file a:1K
  [[ ! -e big.img ]] || die "a failed disk create left big.img"
  cp ref.dream copy.dream
  expect 1 "^seqslam: error: copy.dream: " limited "$SEQSLAM" convert images-to-dream \
    "$DATA/corridor/query" copy.dream --size 32x16
  same ref.dream copy.dream
  no_temporaries
  # sweep appends row by row: the rows written stay, the count is the real one, no "done";
  # the next run resumes and completes.
  grid=(--pair ref.dream,query.dream,gt.csv --seq-len 5,10,20,30 --window 0,20,50)
  expect 1 "^seqslam: error: sweep.csv: write failed: File too large: [0-9]+ of 12 rows are in the file" \
    limited "$SEQSLAM" sweep "${grid[@]}" --out sweep.csv
  if grep -q "done" out.txt; then
    show
    die "sweep to a full file says done"
  fi
  rows=$(grep -Eo '[0-9]+ of 12 rows' err.txt | cut -d' ' -f1)
  [[ $(grep -c '' sweep.csv) -ge $((rows + 1)) ]] || die "sweep.csv has fewer than $rows rows"
  ok "$SEQSLAM" sweep "${grid[@]}" --out sweep.csv
  out_has "^sweep: 12 combinations x pairs, $rows already in sweep.csv, $((12 - rows)) to run$" \
    "^sweep: done, 12 rows in sweep.csv$"
  [[ $(wc -l <sweep.csv) -eq 13 ]] || die "expected header + 12 rows after resuming"
  ;;

size_limit)
  make_inputs
  # 1 KiB files (bash counts 1024-byte blocks); SIGXFSZ is not trapped: the tools ignore it
  # themselves, so the write fails with EFBIG instead of the signal killing them (status 153,
  # no message, the temporary left behind). Standard output and error stay below 1 KiB.
  limited() { (ulimit -f 1 && exec "$@"); }
  efbig="File too large"
  # too_big FILE STATUS REGEX CMD...: CMD fails under the limit; FILE is as it was (absent, or
  # its copy FILE.orig), and no temporary is left.
  too_big() {
    local file=$1 want=$2 regex=$3
    shift 3
    expect "$want" "$regex" limited "$@"
    if [[ -e $file.orig ]]; then
      same "$file.orig" "$file"
    else
      [[ ! -e $file ]] || die "$* under ulimit -f left $file"
    fi
    no_temporaries
  }
  printf 'old\n' >kept.csv
  cp kept.csv kept.csv.orig
  too_big kept.csv 1 "^seqslam: error: kept.csv: write failed: $efbig" \
    "$SEQSLAM" results r.img --csv kept.csv
  too_big big.img 1 "^seqslam: error: big.img: cannot size disk image: $efbig$" \
    "$SEQSLAM" disk create big.img --size 1M --file a:1K
  too_big replay.bin 1 "^seqslam: error: replay.bin: write failed: $efbig" \
    "$SEQSLAM" disk export r.img replay replay.bin
  too_big new.dream 1 "^seqslam: error: new.dream: cannot size disk image: $efbig" \
    "$SEQSLAM" convert images-to-dream "$DATA/corridor/query" new.dream --size 32x16
  # (Each image is below 1 KiB; the index of 111 lines is not.)
  too_big pngs/index.txt 1 "^seqslam: error: pngs/index.txt: write failed: $efbig" \
    "$SEQSLAM" convert dream-to-images ref.dream pngs --format pgm --index pngs/index.txt
  too_big e.json 1 "^seqslam: error: e.json: write failed: $efbig$" \
    "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --json e.json --quiet
  too_big e.html 1 "^seqslam: error: e.html: write failed: $efbig$" \
    "$SEQSLAM" eval ref.dream query.dream --ground-truth gt.csv --report e.html --quiet
  too_big run.csv 1 "^seqslam: error: run.csv: write failed: $efbig" \
    "$SEQSLAM" run ref.dream query.dream --csv run.csv
  too_big rep.html 1 "^seqslam: error: rep.html: write failed: $efbig$" \
    "$SEQSLAM" report ref.dream query.dream --ground-truth gt.csv --out rep.html
  # A sweep appends in place: the rows that fitted stay (too_large resumes such a file).
  expect 1 "^seqslam: error: sweep.csv: write failed: $efbig: [0-9]+ of 12 rows are in the file" \
    limited "$SEQSLAM" sweep --pair ref.dream,query.dream,gt.csv --seq-len 5,10,20,30 \
    --window 0,20,50 --out sweep.csv --quiet
  no_temporaries
  # tune's report of 12 pairs (rows made up: tune reads figures, it does not evaluate).
  {
    echo "library,query,ground_truth,size,preprocess,seq_len,window,exclusion,threshold,max_shift,matcher,metric,queries,top1,recall_at_100_precision,auc_pr,precision_at_recall_0.5,precision_at_recall_0.85,max_recall,accepted,precision,recall,match_ms"
    for p in $(seq 12); do
      for s in 10 30; do
        echo "lib$p.dream,query$p.dream,gt$p.csv,32x16,he,$s,50,10,0.85,0,diagonal,mad,100,0.5,0.$p,0.5,0.5,0.5,0.9,10,0.9,0.1,1.5"
      done
    done
  } >rows.csv
  ok "$SEQSLAM" tune rows.csv --out tune.md
  [[ $(stat -c %s tune.md) -gt 1024 ]] || die "tune.md is too small to test the limit"
  rm tune.md
  too_big tune.md 1 "^seqslam: error: tune.md: write failed: $efbig$" \
    "$SEQSLAM" tune rows.csv --out tune.md
  # Standard output (a file under the same limit).
  run limited "$SEQSLAM" explain --all
  [[ $status -eq 1 ]] && grep -q "^seqslam: error: writing standard output: $efbig$" err.txt || {
    show
    die "explain --all to a file beyond the limit: status $status"
  }
  # The simulator's and the demo's writers.
  too_big m.png 1 "^seqslam-sim: m.png: write failed: $efbig$" "$SIM" montage ref.dream --count 50 --out m.png
  too_big v_camera.png 1 "^seqslam-sim: v_camera.png: write failed: $efbig$" "$SIM" render --out v
  too_big g/short_noon-lamps.dream 1 \
    "^seqslam-sim: g/short_noon-lamps.dream: cannot size disk image: $efbig$" \
    "$SIM" generate --scenario short --seed 1 --out g
  run limited "$DEMO" --data "$DATA/corridor"
  [[ $status -eq 1 ]] && grep -q "seqslam-demo: writing standard output: $efbig" err.txt || {
    show
    die "seqslam-demo to a file beyond the limit: status $status"
  }
  ;;

devices_kept)
  make_inputs
  mkfifo pipe
  expect 1 "^seqslam: error: pipe: is a FIFO or socket" "$SEQSLAM" disk create pipe --file a:1K
  [[ -p pipe ]] || die "disk create removed the FIFO"
  expect 1 "^seqslam: error: pipe: is a FIFO or socket" "$SEQSLAM" convert images-to-dream \
    imgs pipe --size 32x16
  [[ -p pipe ]] || die "images-to-dream removed the FIFO"
  # A stream output into a FIFO is written in place.
  ok "$SEQSLAM" results r.img --csv file.csv
  timeout 60 cat pipe >piped.csv &
  reader=$!
  ok "$SEQSLAM" results r.img --csv pipe
  wait "$reader"
  same file.csv piped.csv
  [[ -p pipe ]] || die "results --csv removed the FIFO"
  # ... and never read as an input (issue 34: a reader would block or never end).
  mkdir set
  mkfifo set/pairs.csv
  expect 1 "^seqslam-sim: set/pairs.csv: is not a regular file" timeout 60 "$SIM" evaluate set
  expect 1 "^seqslam: error: pipe: is not a regular file" timeout 60 "$SEQSLAM" tune pipe
  expect 1 "^seqslam: error: pipe: is not a regular file" timeout 60 "$SEQSLAM" sweep \
    --pairs pipe --out rows.csv
  # A device node (a copy of /dev/full; needs CAP_MKNOD).
  if mknod full c 1 7 2>/dev/null; then
    expect 1 "^seqslam: error: full: cannot write disk image: No space left on device$" \
      "$SEQSLAM" disk create full --file a:1K
    [[ -c full ]] || die "disk create removed the device node"
    expect 1 "^seqslam: error: full: write failed: No space left on device" \
      "$SEQSLAM" results r.img --csv full
    [[ -c full ]] || die "results --csv removed the device node"
  else
    echo "note: mknod not permitted, device node part skipped"
  fi
  no_temporaries
  ;;

interrupted)
  # A sparse 500 GiB FROM: copying it (reading its holes) takes far longer than a second,
  # while the image stays sparse. SIGTERM after a second: no image, no temporary.
  truncate -s 500G huge.bin
  run timeout -k 20 -s TERM 1 "$SEQSLAM" disk create x.img --file a::huge.bin
  [[ $status -eq 124 ]] || {
    show
    die "disk create was not interrupted (status $status)"
  }
  [[ ! -e x.img ]] || die "the interrupted disk create left x.img"
  no_temporaries
  # An existing image stays as it was.
  ok "$SEQSLAM" disk create x.img --file a:1K
  cp x.img x.orig
  run timeout -k 20 -s TERM 1 "$SEQSLAM" disk create x.img --file a::huge.bin
  [[ $status -eq 124 ]] || die "disk create was not interrupted (status $status)"
  same x.orig x.img
  no_temporaries
  rm -f huge.bin
  ;;

sparse)
  start=$(date +%s%N)
  ok "$SEQSLAM" disk create big.img --size 2047G --file a:1K --file b:1M
  ms=$((($(date +%s%N) - start) / 1000000))
  out_has "^big.img: 4292870144 blocks \(2197949513728 bytes\), 2 files, 4292868093 blocks unused$"
  [[ $ms -lt 1000 ]] || die "disk create --size 2047G took $ms ms"
  size_is big.img 2197949513728
  allocated=$(stat -c %b big.img)
  [[ $allocated -le 256 ]] || die "big.img has $allocated blocks allocated: not sparse"
  ok "$SEQSLAM" disk list big.img
  out_has "^a +1 +2 +1024 +empty \(zeros\)$" "^b +3 +2048 +1048576 +empty \(zeros\)$"
  # FROM files are copied; their zeros are not written (the image stays sparse).
  head -c 4096 /dev/urandom >data.bin
  truncate -s 8M data.bin
  ok "$SEQSLAM" disk create d.img --file data::data.bin
  allocated=$(stat -c %b d.img)
  [[ $allocated -le 256 ]] || die "d.img has $allocated blocks allocated: zeros were written"
  ok "$SEQSLAM" disk export d.img data exported.bin
  same data.bin exported.bin
  rm -f big.img  # 2 TiB apparent size: not for backups or du --apparent-size to trip over
  ;;

montage)
  ok "$SEQSLAM" convert images-to-dream "$DATA/corridor/ref" ref.dream --size 32x16
  # Clamped to the places there are: 111 rows of 16 * 4 + 4 pixels.
  ok "$SIM" montage ref.dream --count 4294967295 --out m.png
  python3 - m.png <<'EOF' || die "m.png is not 132x7548"
import struct, sys
data = open(sys.argv[1], "rb").read(24)
assert data[:8] == b"\x89PNG\r\n\x1a\n" and struct.unpack(">II", data[16:24]) == (132, 7548), data
EOF
  ok "$SIM" montage ref.dream --first 100 --step 5 --count 4294967295 --out m3.png
  expect 2 "^seqslam-sim: --count 4294967295: a sheet of 4294967295 rows would be" \
    "$SIM" montage ref.dream --step 0 --count 4294967295 --out m2.png
  expect 2 "^seqslam-sim: --first 4294967295: the recordings have 111 places" \
    "$SIM" montage ref.dream --first 4294967295 --out m2.png
  [[ ! -e m2.png ]] || die "a refused montage wrote m2.png"
  no_temporaries
  ;;

*)
  die "unknown case '$CASE'"
  ;;
esac
echo PASS
