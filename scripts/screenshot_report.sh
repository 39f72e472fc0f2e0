#!/usr/bin/env bash
# Renders DIR/report/index.html once in headless Chromium and checks the
# screenshot is not blank.
#   scripts/screenshot_report.sh DIR [OUT.png]
#   scripts/screenshot_report.sh --fixture    (self-contained, for ctest: builds
#       a synthetic DIR with reports/make_fixture.py and its report in a temp
#       dir first)
# OUT.png defaults to DIR/report/screenshot.png. Exit codes: 0 rendered and
# not blank, 1 blank or failed render, 2 bad usage / no index.html,
# 77 skipped (no chromium installed).
set -euo pipefail
source "$(dirname "$0")/screenshot_common.sh"

screenshot_usage "$@"
dir=$1
tmp_fixture=""
if [ "$dir" = "--fixture" ]; then
  find_chromium screenshot_report
  root=$(cd "$(dirname "$0")/.." && pwd)
  tmp_fixture=$(mktemp -d)
  dir="$tmp_fixture/results"
  make_fixture_report "$root" "$dir"
fi
index=$(page_path screenshot_report "$dir/report/index.html" \
  "run reports/make_report.py $dir first")
out=${2:-$(dirname "$index")/screenshot.png}

find_chromium screenshot_report

profile=$(mktemp -d)
trap 'rm -rf "$profile" ${tmp_fixture:+"$tmp_fixture"}' EXIT
rm -f "$out"
timeout 120 "$browser" --headless --no-sandbox --disable-gpu --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync \
  --user-data-dir="$profile" --screenshot="$out" --window-size=1280,2000 \
  "file://$index" > "$profile/chromium.log" 2>&1 || {
  echo "screenshot_report: chromium failed: $(tail -n 1 "$profile/chromium.log")" >&2
  exit 1
}
if [ ! -s "$out" ]; then
  echo "screenshot_report: chromium wrote no screenshot" >&2
  exit 1
fi

MPLBACKEND=Agg /usr/bin/python3 - "$out" <<'EOF'
import sys
import matplotlib.image

pixels = matplotlib.image.imread(sys.argv[1])
std = float(pixels[..., :3].std())
if std < 0.02:
    print(f"screenshot_report: {sys.argv[1]} looks blank (pixel std {std:.4f})",
          file=sys.stderr)
    sys.exit(1)
print(f"screenshot_report: {sys.argv[1]} {pixels.shape[1]}x{pixels.shape[0]}, "
      f"pixel std {std:.3f}")
EOF
echo "$out"
