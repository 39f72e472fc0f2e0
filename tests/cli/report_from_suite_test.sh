#!/usr/bin/env bash
# The report generator on real harness output: run a small suite, render the
# report, check index.html references every figure and each PNG is a valid,
# non-empty image.   tests/cli/report_from_suite_test.sh QUASIROLL_BINARY
set -euo pipefail
bin=$1
cd "$(dirname "$0")/../.."
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bin" bench --suite tests/data/suites/report_fixture.yaml --out "$out" --jobs 2 > "$out/bench.log" 2>&1
index=$(/usr/bin/python3 reports/make_report.py --strict "$out" 2> "$out/report.log" | tail -n 1)
[ -f "$index" ] || { echo "no index.html: $(cat "$out/report.log")"; exit 1; }
/usr/bin/python3 - "$out/report" <<'PY'
import json, os, re, struct, sys
report = sys.argv[1]
html = open(os.path.join(report, "index.html"), encoding="utf-8").read()
figures = json.load(open(os.path.join(report, "figures.json")))
pngs = sorted(f for f in os.listdir(report) if f.endswith(".png"))
assert len(pngs) >= 14, pngs  # 3 comparison figures + 11 paper figures
failed = 0
for name in pngs:
    data = open(os.path.join(report, name), "rb").read()
    ok = data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 2000
    width, height = struct.unpack(">II", data[16:24])
    ok = ok and width > 200 and height > 200 and name in html
    ok = ok and os.path.exists(os.path.join(report, name[:-4] + ".svg"))
    if not ok:
        failed += 1
        print("bad figure", name, width, height)
# The robot drawn by Fig. 5 and the 3D replay (reports/quasiroll_report/robot.py)
# must touch the terrain where the harness says: every recorded contact point
# lies on its drawn torus (closed-form distance). The pose is chain 1's, so
# wheels 2 and 3 are off by up to the loop-closure drift ||H|| of that row;
# allowed: 1e-9 m (CSV round trip) + 2 ||H|| (m and rad at lever arms < 1 m).
# Successful runs only (a failed run may stop with a broken configuration).
sys.path.insert(0, "reports")
from quasiroll_report import robot
from quasiroll_report.data import read_trajectory
results = os.path.dirname(report)
geom = {"a": 0.25, "b": 0.25, "track": 0.4, "z_h": 0.05, "R": 0.08, "r": 0.02, "e": 0.0}
import csv
ok_ids = [r["run_id"] for r in csv.DictReader(open(os.path.join(results, "runs.csv")))
          if r["status"] == "success"]
worst, checked = -1.0, 0
for run_id in ok_ids:
    traj = read_trajectory(os.path.join(results, "trajectories", run_id + ".csv"))
    for k in range(len(traj["t"])):
        row = robot.row_at(traj, k)
        if not robot.finite_pose(row):
            continue
        for i, (rot, centre) in enumerate(robot.wheel_frames_world(geom, row), start=1):
            point = [row[f"c{i}_x"], row[f"c{i}_y"], row[f"c{i}_z"]]
            if all(map(lambda v: v == v, point)):
                excess = robot.torus_residual(geom, rot, centre, point) - 2 * row["drift"]
                worst = max(worst, excess)
                checked += 1
print(f"contact points on the drawn wheels: {checked} checked, "
      f"worst (distance - 2 ||H||) {worst:.2e} m")
if checked == 0 or worst > 1e-9:
    failed += 1
    print("bad robot geometry: contact point off its drawn torus")
replay = os.path.join(report, "replay", "data.js")
if os.path.isfile("/usr/share/javascript/three/three.min.js"):
    text = open(replay, encoding="utf-8").read()
    data = json.loads(text[text.index("=") + 1:].rstrip().rstrip(";"))
    if not data or not data[0]["frames"]:
        failed += 1
        print("replay data has no frames")
print(f"{len(pngs) - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
PY
