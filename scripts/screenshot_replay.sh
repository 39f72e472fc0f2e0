#!/usr/bin/env bash
# Checks the report's 3D replay (DIR/report/replay/index.html) in headless
# Chromium with software WebGL (SwiftShader):
#   1. the page reaches <body data-ready="1"> (three.js loaded, WebGL context,
#      first frame rendered);
#   2. a screenshot shows the robot: at least MIN_ROBOT_PIXELS pixels of the
#      unlit magenta chassis colour, and wheel-dark pixels;
#   3. negative control: with ?norobot=1 the same screenshot has (almost) no
#      chassis pixels, so check 2 can fail.
#   scripts/screenshot_replay.sh DIR [OUT.png]
#   scripts/screenshot_replay.sh --fixture    (self-contained, for ctest)
# Exit codes: 0 pass, 1 check failed, 2 bad usage / no replay page,
# 77 skipped (no chromium, or no libjs-three so the report has no replay).
set -euo pipefail
source "$(dirname "$0")/screenshot_common.sh"
screenshot_usage "$@"
find_chromium screenshot_replay
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
dir=$1
if [ "$dir" = "--fixture" ]; then
  if [ ! -f /usr/share/javascript/three/three.min.js ]; then
    echo "screenshot_replay: libjs-three not installed, skipping" >&2
    exit 77
  fi
  dir="$work/results"
  make_fixture_report "$root" "$dir"
fi
page=$(page_path screenshot_replay "$dir/report/replay/index.html" \
  "report written without libjs-three?")
out=${2:-$work/replay.png}

chrome() {
  timeout 120 "$browser" --headless --no-sandbox --use-angle=swiftshader \
    --enable-unsafe-swiftshader --no-first-run --disable-background-networking \
    --disable-component-update --disable-sync --user-data-dir="$work/profile" \
    --virtual-time-budget=10000 --window-size=1000,640 "$@" 2> "$work/chromium.log"
}

chrome --dump-dom "file://$page?frame=1" > "$work/dom.html" || {
  echo "screenshot_replay: chromium failed: $(tail -n 1 "$work/chromium.log")" >&2
  exit 1
}
if ! grep -q '<body data-ready="1"' "$work/dom.html"; then
  echo "screenshot_replay: page not ready: $(grep -o '<body[^>]*>' "$work/dom.html" | head -1)" \
       "$(grep -o '<span id="status">[^<]*' "$work/dom.html" | head -1)" >&2
  exit 1
fi
chrome --screenshot="$out" "file://$page?frame=1" > /dev/null || true
chrome --screenshot="$work/norobot.png" "file://$page?frame=1&norobot=1" > /dev/null || true
for f in "$out" "$work/norobot.png"; do
  [ -s "$f" ] || { echo "screenshot_replay: no screenshot $f" >&2; exit 1; }
done

MPLBACKEND=Agg /usr/bin/python3 - "$out" "$work/norobot.png" <<'PY'
import sys
import matplotlib.image
import numpy as np

MIN_ROBOT_PIXELS = 300


def counts(path):
    px = matplotlib.image.imread(path)[..., :3]
    r, g, b = px[..., 0], px[..., 1], px[..., 2]
    chassis = int(np.sum((r > 0.85) & (g < 0.25) & (b > 0.85)))   # #ff00ff, unlit
    dark = int(np.sum((r < 0.3) & (g < 0.3) & (b < 0.3)))          # wheels #303030
    return chassis, dark


robot, robot_dark = counts(sys.argv[1])
empty, empty_dark = counts(sys.argv[2])
print(f"screenshot_replay: chassis pixels {robot} (without robot {empty}), "
      f"dark wheel pixels {robot_dark} (without robot {empty_dark})")
ok = robot >= MIN_ROBOT_PIXELS and empty < 10 and robot_dark > empty_dark + 50
if not ok:
    print("screenshot_replay: the robot is not visible in the replay screenshot",
          file=sys.stderr)
sys.exit(0 if ok else 1)
PY
echo "$out"
