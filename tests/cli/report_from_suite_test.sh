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
print(f"{len(pngs) - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
PY
