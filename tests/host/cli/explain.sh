# seqslam explain: the sentences behind the board's message codes (include/seqslam/messages.h).
# Every enumerator of the thirteen enums (counted in the headers here, independently of the
# tool's table) has a code, docs/messages.md is exactly `seqslam explain --all`, and bad codes
# are usage errors. Usage: explain.sh SOURCE_DIR
source "$(dirname "$0")/lib.sh"
SRC=${1:?source directory}
DOC="$SRC/docs/messages.md"

# family code, enum name, header
families=(
  "CI ConfigIssue include/seqslam/localiser.h"
  "RI RouteIssue include/seqslam/route_search.h"
  "HI HeuristicIssue include/seqslam/heuristic_matcher.h"
  "GI GridIssue include/seqslam/occupancy_grid.h"
  "EI ExplorerIssue include/seqslam/explorer.h"
  "LP LogProblem storage/include/seqslam/storage/record_log.h"
  "DP DreamProblem storage/include/seqslam/storage/dream.h"
  "PL LibraryProblem storage/include/seqslam/storage/library_store.h"
  "VP VolumeProblem storage/include/seqslam/storage/volume.h"
  "MP MapProblem storage/include/seqslam/storage/map_store.h"
  "RC RunIssue storage/include/seqslam/storage/run_config.h"
  "SE SessionIssue session/include/seqslam/session/session.h"
  "FW FirmwareIssue session/include/seqslam/session/session.h"
)

# enumerators NAME HEADER: the enumerators of `enum class NAME`, one a line.
enumerators() {
  awk -v name="$1" '
    $0 ~ "^enum class " name " : uint8_t \\{" { inside = 1; next }
    inside && /^};/ { exit }
    inside && match($0, /^ *k[A-Za-z0-9_]+/) { e = substr($0, RSTART, RLENGTH); gsub(/ /, "", e); print e }
  ' "$SRC/$2"
}

ok "$SEQSLAM" explain --all
cp out.txt all.md
[[ ! -s err.txt ]] || die "explain --all wrote to stderr: $(cat err.txt)"
out_has "^\| code \| family \| value \| message \|$" "^\| --- \| --- \| --- \| --- \|$"
rows=2
for f in "${families[@]}"; do
  read -r code name header <<<"$f"
  mapfile -t names < <(enumerators "$name" "$header")
  n=${#names[@]}
  [[ $n -ge 2 ]] || die "$header: no enum class $name found"
  [[ ${names[0]} == kNone ]] || die "$name: the first enumerator is ${names[0]}, not kNone"
  # Values 0..n-1 without gaps: only kNone has an explicit value.
  explicit=$(awk -v name="$name" '
      $0 ~ "^enum class " name " : uint8_t \\{" { inside = 1; next }
      inside && /^};/ { exit }
      inside && /^ *k[A-Za-z0-9_]+ *=/ { n++ }
      END { print n + 0 }' "$SRC/$header")
  [[ $explicit -eq 1 ]] || die "$name: explicit values besides kNone = 0; the table assumes 0..n-1"
  # One row per enumerator, in order, and nothing beyond: a new enumerator fails here.
  got=$(grep -c "^| ${code}[0-9]* | $name | " all.md || true)
  [[ $got -eq $n ]] || die "$name has $n enumerators in $header, explain --all lists $got"
  for ((v = 0; v < n; ++v)); do
    grep -Eq "^\| $code$v \| $name \| $v \| .+ \|$" all.md || die "no row for $code$v"
  done
  rows=$((rows + n))
  # The last value decodes, the one after it is refused.
  last=$((n - 1))
  ok "$SEQSLAM" explain "$code$last"
  out_has "^$code$last: $name $last: .+$"
  expect 2 "'$code$n': $name has the values 0..$last \($code""0..$code$last\)" \
    "$SEQSLAM" explain "$code$n"
  [[ ! -s out.txt ]] || die "nothing on stdout for a refused code"
done
[[ $(wc -l <all.md) -eq $rows ]] || die "explain --all has $(wc -l <all.md) lines, expected $rows"

# docs/messages.md holds exactly this table between its markers.
sed -n '/^<!-- begin: seqslam explain --all -->$/,/^<!-- end: seqslam explain --all -->$/p' \
  "$DOC" | sed '1d;$d' >doc_table.md
[[ -s doc_table.md ]] || die "$DOC has no table between the markers"
cmp -s all.md doc_table.md || {
  diff -u doc_table.md all.md >&2 || true
  die "$DOC is out of date: replace its table with the output of 'seqslam explain --all'"
}

# One code: "CODE: Family value: sentence", the sentence of the table's row; any case;
# several at once.
ok "$SEQSLAM" explain PL10
out_has "^PL10: LibraryProblem 10: .+$"
sentence=$(sed -n 's/^PL10: LibraryProblem 10: //p' out.txt)
grep -qxF "| PL10 | LibraryProblem | 10 | $sentence |" all.md || die "PL10 differs from its row"
cp out.txt upper.txt
ok "$SEQSLAM" explain pl10
same upper.txt out.txt
ok "$SEQSLAM" explain Pl010
same upper.txt out.txt
ok "$SEQSLAM" explain MP0 ci4 lp10
out_has "^MP0: MapProblem 0: ok$" "^CI4: ConfigIssue 4: sequence.seq_len must be 1..100" \
  "^LP10: LogProblem 10: end of log: the last record is incomplete or damaged"
[[ $(wc -l <out.txt) -eq 3 ]] || die "one line per code"

# Bad codes: status 2, the problem on stderr, nothing on stdout.
bad() {
  expect 2 "$1" "$SEQSLAM" explain "${@:2}"
  [[ ! -s out.txt ]] || die "stdout not empty for explain ${*:2}"
}
bad "'ZZ3': unknown family 'ZZ' \(the families are CI ConfigIssue, RI RouteIssue, .*MP MapProblem, RC RunIssue, SE SessionIssue, FW FirmwareIssue\)" ZZ3
bad "'PL999999999999999999': LibraryProblem has the values 0\.\." PL999999999999999999
for garbage in PL PL1x 12 PL-1 " PL1" "PL1 " "P1" "PL+1" "PL1.0" "" "PLL1"; do
  quoted=$(printf '%s' "$garbage" | sed 's/[][\.*^$+?(){}|]/\\&/g')
  bad "'$quoted' is not a message code: two letters \(the family\) and a number" "$garbage"
done
# A bad code among good ones: nothing is printed.
bad "'XX1': unknown family" PL10 XX1
bad "give a message CODE \(e.g. PL10\) or --all"
bad "give either CODE... or --all, not both" --all PL10
bad "--bogus" --bogus
echo PASS
