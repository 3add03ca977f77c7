#!/usr/bin/env bash
# Runs one benchmark image under QEMU (-icount shift=0: deterministic instruction counts),
# prints its report and writes the JSON summary it emits to <out-dir>/summary.json (the raw
# console output to <out-dir>/bench.log). `make bench` calls it once per image:
# seqslam_bench.elf -> build/bench, seqslam_bench_mapping.elf -> build/bench/mapping.
# Usage: run-bench.sh <bench.elf> <out-dir>
set -euo pipefail
elf=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out"
log="$out/bench.log"
"$here/qemu-run.sh" "$elf" | tee "$log.raw" | sed '/^BEGIN_SUMMARY_JSON$/,/^END_SUMMARY_JSON$/d'
sed -n '/^BEGIN_SUMMARY_JSON$/,/^END_SUMMARY_JSON$/p' "$log.raw" | sed '1d;$d' > "$out/summary.json"
mv "$log.raw" "$log"
if [ ! -s "$out/summary.json" ]; then
  echo "run-bench: the firmware printed no summary (see $log)" >&2
  exit 1
fi
echo
echo "summary written to $out/summary.json"
