# Helpers for the seqslam command-line tests, sourced by every script here. ctest sets
#   SEQSLAM       the tool (build/<preset>/bin/seqslam)
#   CLI_FIXTURES  the fixture program (cli_fixtures.cpp)
#   WORK          this test's scratch directory (recreated)
#   DATA          tests/data
set -euo pipefail
: "${SEQSLAM:?}" "${CLI_FIXTURES:?}" "${WORK:?}" "${DATA:?}"
# Under ASan/UBSan a sanitizer report must never pass for an expected failure status.
export ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}exitcode=86"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:+$UBSAN_OPTIONS:}exitcode=87:print_stacktrace=1"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

die() {
  echo "FAIL: $*" >&2
  exit 1
}

show() {
  {
    echo "--- stdout"
    cat out.txt
    echo "--- stderr"
    cat err.txt
  } >&2
}

# run CMD...: runs CMD with stdout to out.txt, stderr to err.txt, its exit status in $status.
run() {
  set +e
  "$@" >out.txt 2>err.txt
  status=$?
  set -e
  if grep -Eq "Sanitizer|runtime error:" err.txt; then
    show
    die "sanitizer report from '$*'"
  fi
}

# expect STATUS REGEX CMD...: CMD exits with STATUS and its stderr matches REGEX
# (grep -E; an empty REGEX checks only the status).
expect() {
  local want=$1 regex=$2
  shift 2
  run "$@"
  if [[ $status -ne $want ]]; then
    show
    die "'$*' exited with $status, expected $want"
  fi
  if [[ -n $regex ]] && ! grep -Eq -- "$regex" err.txt; then
    show
    die "stderr of '$*' does not match /$regex/"
  fi
}

# ok CMD...: CMD succeeds.
ok() {
  expect 0 "" "$@"
}

# out_has REGEX...: every REGEX matches a line of the last command's stdout.
out_has() {
  local r
  for r in "$@"; do
    grep -Eq -- "$r" out.txt || {
      show
      die "stdout does not match /$r/"
    }
  done
}

# err_has REGEX...: likewise for stderr.
err_has() {
  local r
  for r in "$@"; do
    grep -Eq -- "$r" err.txt || {
      show
      die "stderr does not match /$r/"
    }
  done
}

# same FILE1 FILE2: byte-identical.
same() {
  cmp -- "$1" "$2" >&2 || die "$1 and $2 differ"
}

# size_is FILE BYTES
size_is() {
  local n
  n=$(stat -c %s -- "$1")
  [[ $n -eq $2 ]] || die "$1 has $n bytes, expected $2"
}

# flip_byte FILE OFFSET: inverts every bit of one byte in place.
flip_byte() {
  local v
  v=$(od -An -tu1 -j "$2" -N1 -- "$1" | tr -d ' ')
  # shellcheck disable=SC2059
  printf "\\$(printf %03o $((v ^ 255)))" | dd of="$1" bs=1 seek="$2" conv=notrunc status=none
}
