# Every subcommand answers --help with status 0, its usage line and options with units.
source "$(dirname "$0")/lib.sh"

for sub in "" "disk" "disk create" "disk list" "disk export" "disk import" "config" \
  "config write" "config show" "results" "convert" "convert images-to-dream" \
  "convert dream-to-images" "dream" "dream info" "explain"; do
  # shellcheck disable=SC2086
  ok "$SEQSLAM" $sub --help
  out_has "^Usage: seqslam ${sub:+$sub }"
done

run "$SEQSLAM" disk create --help
out_has "bytes" "512-byte blocks" "K, M or G"
run "$SEQSLAM" config write --help
out_has "metres" "grey levels" "places" "pixels" "W \* H <= 512" "Default 0.85" "Default 12x10"
out_has "--route-window N" "--route-slack N" "--route-growth X" "--lost-after N" "--scan-places N" \
  "--scan-seq-len N" "--start PLACE\|unknown" "Default 0.05" "Default 25"
run "$SEQSLAM" explain --help
out_has "CODE" "--all" "Markdown" "PL LibraryProblem"
run "$SEQSLAM" results --help
out_has "metres" "degrees" "microseconds" "step,capture,timestamp_us,x_m,y_m,heading_deg"
out_has "--ground-truth FILE" "--threshold C" "--json OUT" "the run configuration" "0.85"
run "$SEQSLAM" convert images-to-dream --help
out_has "W \* H <= 512" "microseconds"

ok "$SEQSLAM" --version
out_has "^[0-9]+\.[0-9]+\.[0-9]+"

# No subcommand, an unknown one, an unknown option: usage errors.
expect 2 "subcommand is required" "$SEQSLAM"
expect 2 "subcommand is required" "$SEQSLAM" disk
expect 2 "" "$SEQSLAM" frobnicate
expect 2 "--bogus" "$SEQSLAM" disk list x.img --bogus
expect 2 "IMAGE is required" "$SEQSLAM" disk list
echo PASS
