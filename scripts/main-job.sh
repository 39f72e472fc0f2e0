#!/usr/bin/env bash
# The main job: build quasiroll, then show the paper scene's initial
# configuration. (Becomes: run the default benchmark suite and its report.)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build -j "$(nproc 2>/dev/null || echo 2)" --target quasiroll
./build/bench/quasiroll pose --scene bench/scenes/paper.yaml
