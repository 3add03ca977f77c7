#!/usr/bin/env bash
# Runs every libFuzzer target of the fuzz preset (tests/fuzz, docs/fuzzing.md) for a budget
# and prints one row per target: executions, seconds, executions per second, result.
#
#   FUZZ_RUNS=10000000 scripts/fuzz.sh     # a number of executions per target
#   FUZZ_SECONDS=300 scripts/fuzz.sh       # or a time per target (the default, 300 s)
#   FUZZ_JOBS=2                            # targets run side by side (default 1)
#   FUZZ_SEED=7                            # libFuzzer's seed (default 1: repeatable)
#
# Needs the built fuzz preset and its seed corpora (make test-fuzz makes both; `make fuzz`
# calls this script after it). Corpora grow in build/fuzz/tests/fuzz/<target>_corpus;
# a failing input is written to build/fuzz/artifacts/ and the script exits 1.
# Logs: build/fuzz/logs/<target>.log; the table also goes to build/fuzz/summary.md.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=build/fuzz/tests/fuzz
[[ -x $dir/fuzz_record_log ]] || { echo "fuzz.sh: build the fuzz preset first (make test-fuzz)" >&2; exit 2; }

if [[ -n ${FUZZ_RUNS:-} ]]; then
  [[ $FUZZ_RUNS =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: FUZZ_RUNS must be a positive integer" >&2; exit 2; }
  budget=(-runs="$FUZZ_RUNS")
else
  seconds=${FUZZ_SECONDS:-300}
  [[ $seconds =~ ^[1-9][0-9]*$ ]] || { echo "fuzz.sh: FUZZ_SECONDS must be a positive integer" >&2; exit 2; }
  budget=(-max_total_time="$seconds")
fi
jobs=${FUZZ_JOBS:-1}
seed=${FUZZ_SEED:-1}
[[ $jobs =~ ^[1-9]$ && $seed =~ ^[0-9]+$ ]] || { echo "fuzz.sh: FUZZ_JOBS 1-9, FUZZ_SEED an integer" >&2; exit 2; }

mkdir -p build/fuzz/logs build/fuzz/artifacts
# target, seed corpus made by the ctest fixtures (copied once into the growing corpus), -max_len
targets=(
  "record_log - 512"
  "dream_damage - 512"
  "map_graph - 8192"
  "dream_reader dream_corpus 16384"
  "library_loader library_corpus 16384"
  "image_loader image_corpus 16384"
)

run_one() {
  local name=$1 seeds=$2 max_len=$3
  local corpus=$dir/${name}_corpus log=build/fuzz/logs/$name.log
  mkdir -p "$corpus"
  if [[ $seeds != - && -d $dir/$seeds ]] && [[ -z $(ls -A "$corpus") ]]; then
    cp "$dir/$seeds"/* "$corpus"/
  fi
  local start end status=0
  start=$(date +%s)
  "$dir/fuzz_$name" -seed="$seed" "${budget[@]}" -max_len="$max_len" -print_final_stats=1 \
    -artifact_prefix=build/fuzz/artifacts/"$name"- "$corpus" >"$log" 2>&1 || status=$?
  end=$(date +%s)
  local runs
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  runs=${runs:-0}
  local secs=$((end - start))
  local rate=$((runs / (secs > 0 ? secs : 1)))
  local result="no violation"
  [[ $status -eq 0 ]] || result="FAILED (exit $status; build/fuzz/artifacts/, $log)"
  printf '| `fuzz_%s` | %s | %s s | %s | %s |\n' "$name" "$runs" "$secs" "$rate" "$result" \
    >"build/fuzz/logs/$name.row"
  return "$status"
}

pids=()
failed=0
for t in "${targets[@]}"; do
  # shellcheck disable=SC2086
  run_one $t &
  pids+=($!)
  if [[ ${#pids[@]} -ge $jobs ]]; then
    wait "${pids[0]}" || failed=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || failed=1; done

{
  echo "| target | runs | time | execs/s | result |"
  echo "| --- | --- | --- | --- | --- |"
  for t in "${targets[@]}"; do cat "build/fuzz/logs/${t%% *}.row"; done
} | tee build/fuzz/summary.md
exit "$failed"
