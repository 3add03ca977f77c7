#!/usr/bin/env bash
# The report in a real browser: writes the synthetic reports (full, minimal) with
# report_sample, opens each in headless Chromium with the fragment #selftest and checks what
# the page's own self-test found (sections present, every <img> decoded at its declared size,
# no uniform image, every chart drawn); then takes a screenshot of the full report and checks
# it is not blank. The screenshot stays in WORK_DIR/report_full.png for people to look at.
#
# usage: browser_test.sh REPORT_SAMPLE WORK_DIR
# Needs Debian's chromium (scripts/install-deps.sh installs it); without it the test fails.
set -euo pipefail
sample=$1
work=$2

browser=${CHROMIUM:-}
if [ -z "$browser" ]; then
  browser=$(command -v chromium || command -v chromium-browser || true)
fi
if [ -z "$browser" ] || [ ! -x "$browser" ]; then
  echo "FAIL: chromium is not installed; run scripts/install-deps.sh (or apt-get install -y chromium)" >&2
  exit 1
fi

rm -rf "$work"
mkdir -p "$work"
# --no-sandbox: Chromium refuses to run as root with its sandbox; the page is our own file.
chrome=("$browser" --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run
        --no-default-browser-check --hide-scrollbars --user-data-dir="$work/profile")

status=0
for variant in full minimal; do
  page="$work/report_$variant.html"
  "$sample" html "$page" "$variant"
  timeout 120 "${chrome[@]}" --virtual-time-budget=5000 --dump-dom "file://$page#selftest" \
    >"$work/dom_$variant.html" 2>"$work/chromium_$variant.log" || {
    echo "FAIL: chromium could not load $page (log: $work/chromium_$variant.log)" >&2
    tail -5 "$work/chromium_$variant.log" >&2
    exit 1
  }
  findings=$(sed -n '/<pre id="selftest"/,/<\/pre>/p' "$work/dom_$variant.html")
  echo "--- $variant: the page's self-test"
  echo "$findings" | sed -e 's/<[^>]*>//g'
  if ! grep -q 'selftest: PASS' <<<"$findings"; then
    echo "FAIL: $variant report: the self-test did not pass (DOM: $work/dom_$variant.html)" >&2
    status=1
  fi
  if ! grep -q 'uniform images: 0' <<<"$findings"; then
    echo "FAIL: $variant report: an image is uniform (blank)" >&2
    status=1
  fi
done

shot="$work/report_full.png"
timeout 120 "${chrome[@]}" --window-size=1300,7000 --screenshot="$shot" \
  "file://$work/report_full.html" >"$work/chromium_screenshot.log" 2>&1 || {
  echo "FAIL: chromium could not take a screenshot (log: $work/chromium_screenshot.log)" >&2
  exit 1
}
"$sample" png-check "$shot" || status=1
rm -rf "$work/profile"
echo "screenshot: $shot"
exit $status
