#!/usr/bin/env bash
# The main job: install dependencies, build, run the default benchmark suite
# (bench/suites/default.yaml) and write its comparison report. Ends by
# printing the path of the report's index.html.
#   scripts/main-job.sh [OUT_DIR]          (default: results/default)
# Re-running resumes: finished runs are kept (quasiroll bench --resume).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/default}
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j "$(nproc 2>/dev/null || echo 2)" --target quasiroll
./build/bench/quasiroll bench --suite bench/suites/default.yaml --out "$out" --resume
./build/bench/quasiroll report "$out"
