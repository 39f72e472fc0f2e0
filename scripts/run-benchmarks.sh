#!/usr/bin/env bash
# Runs every Google Benchmark micro-benchmark (NLP backends, integrators, the
# robot kernels) in one go and writes JSON.
#   scripts/run-benchmarks.sh [OUT.json] [extra benchmark flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-benchmarks.json}
shift || true
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j "$(nproc 2>/dev/null || echo 2)" --target quasiroll_benchmarks
./build/bench/quasiroll_benchmarks --benchmark_out="$out" --benchmark_out_format=json "$@"
echo "wrote $out"
