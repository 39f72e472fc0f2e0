#!/usr/bin/env bash
# A shipped suite's results equal the ones recorded in tests/data/golden/<suite>
# (runs.csv without timing/host columns, and every trajectory byte for byte):
# refactorings of the harness and the backends must not change a result.
#   golden_outputs_test.sh <quasiroll> <suite name>
# To record again (only for a deliberate, documented change of results):
#   quasiroll bench --suite bench/suites/<suite>.yaml --out /tmp/g --jobs 2
#   scripts/compare-bench-outputs.py --record-golden /tmp/g tests/data/golden/<suite>
set -euo pipefail
cli=$1
suite=$2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$cli" bench --suite "bench/suites/$suite.yaml" --out "$out/run" --jobs 2 >/dev/null
/usr/bin/python3 scripts/compare-bench-outputs.py --golden "tests/data/golden/$suite" "$out/run"
