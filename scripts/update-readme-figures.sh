#!/usr/bin/env bash
# Regenerates the two figures the README embeds (docs/img/) from a results
# directory of the default suite, running the main job first if needed.
#   scripts/update-readme-figures.sh [RESULTS_DIR]   (default: results/default)
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-results/default}
if [ ! -f "$dir/report/index.html" ]; then
  bash scripts/main-job.sh "$dir"
fi
mkdir -p docs/img
cp "$dir/report/fig_work_precision.png" docs/img/work_precision.png
cp "$dir/report/fig05_snapshots.png" docs/img/paper_fig5_snapshots.png
echo "updated docs/img/work_precision.png docs/img/paper_fig5_snapshots.png from $dir"
