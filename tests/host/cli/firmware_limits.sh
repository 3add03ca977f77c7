# `seqslam config write` refuses what the firmware application refuses at start
# (storage::check_run_config with the application's limits, firmware/app/app_limits.h), with
# the firmware's own sentence, and writes nothing; what it writes at those limits the firmware
# starts with. The refused settings are stored with the fixture (storage::write_run_config: the
# format's checks only) and given to the PC build of the application, which prints its reason.
# Usage: firmware_limits.sh SEQSLAM_FIRMWARE
source "$(dirname "$0")/lib.sh"
FIRMWARE=${1:?seqslam-firmware}
[[ -x $FIRMWARE ]] || die "$FIRMWARE not built (cmake --build ... --target seqslam-firmware)"

# fixture settings | config write options | the status both give
cases=(
  "seq_len=31|--seq-len 31|OUT_OF_RANGE"
  "window=51|--window 51|OUT_OF_RANGE"
  "exclusion=11|--exclusion 11|OUT_OF_RANGE"
  "route_window=35|--route-window 35|OUT_OF_RANGE"
  "scan_seq_len=11|--scan-seq-len 11|OUT_OF_RANGE"
  "max_shift=1|--max-shift 1|INVALID_ARGUMENT"
  "modes=11 matcher=1|--modes explore --matcher heuristic|INVALID_ARGUMENT"
)
for c in "${cases[@]}"; do
  IFS='|' read -r settings options want <<<"$c"
  # The firmware's reason.
  # shellcheck disable=SC2086
  "$CLI_FIXTURES" config-raw cfg.bin $settings || die "config-raw $settings failed"
  rm -f fw.img
  ok "$SEQSLAM" disk create fw.img --file config::cfg.bin
  expect 2 "" "$FIRMWARE" --disk fw.img
  sentence=$(sed -n "s/^app: configuration: $want - //p" out.txt)
  [[ -n $sentence ]] || {
    show
    die "the firmware did not refuse '$settings' with $want"
  }
  # The tool's: the same sentence and status, naming the option; nothing written.
  rm -f tool.img
  ok "$SEQSLAM" disk create tool.img --file config:1K
  # shellcheck disable=SC2086
  expect 2 "" "$SEQSLAM" config write tool.img $options
  grep -Fq -- "invalid configuration for the firmware: $sentence ($want): ${options%% *} " \
    err.txt || {
    show
    die "config write $options: not the firmware's reason '$sentence ($want)'"
  }
  expect 1 "tool.img:config: not a usable run configuration" "$SEQSLAM" config show tool.img
done

# A spacing beyond the trigger's range is outside the settings table's range: refused as the
# option is read, naming the range (no card carries it: the firmware reads one as damaged).
for spacing in 2000 1000.001 0; do
  expect 2 "--spacing: '$spacing' is not above 0 and at most 1000 m" \
    "$SEQSLAM" config write tool.img --spacing "$spacing"
done

# At the limits: written, and the firmware gets past its configuration check (it then stops
# for want of sensors: the image has no replay recording).
ok "$SEQSLAM" disk create lim.img --file config:1K
ok "$SEQSLAM" config write lim.img --seq-len 30 --window 50 --exclusion 10 --route-window 25 \
  --scan-seq-len 10 --spacing 1000
run "$FIRMWARE" --disk lim.img
grep -q "^app: run configuration read from the volume$" out.txt || {
  show
  die "the firmware did not read the configuration at the limits"
}
if grep -q "^app: configuration:" out.txt; then
  show
  die "the firmware refused a configuration config write accepted"
fi
grep -q "^app: no sensors" out.txt || {
  show
  die "the firmware stopped before the sensors"
}
# The heuristic's S is not the diagonal matcher's: up to the core's 100, on the firmware too.
ok "$SEQSLAM" config write lim.img --matcher heuristic --seq-len 100
run "$FIRMWARE" --disk lim.img
if grep -q "^app: configuration:" out.txt; then
  show
  die "the firmware refused the heuristic with S = 100"
fi
echo PASS
