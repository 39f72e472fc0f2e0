#!/usr/bin/env bash
# Queues a quasiroll suite on a Slurm cluster as a job array of N shards and
# a merge job that runs once every shard succeeded (docs/cluster.md):
#
#   scripts/slurm/submit.sh N SUITE DIR [quasiroll bench options, e.g. --filter RE]
#
# DIR must be on a file system every node sees. Environment:
#   QUASIROLL    quasiroll binary (default: build/bench/quasiroll of this checkout)
#   QUASIROLL_SBATCH_ARGS  extra sbatch options for both jobs, e.g.
#                "--partition=short --time=02:00:00 --cpus-per-task=2"
# Prints the two job ids. The results: DIR/runs.csv once the merge job ran;
# then `quasiroll report DIR`.
set -euo pipefail
if [ $# -lt 3 ] || ! [[ "$1" =~ ^[1-9][0-9]*$ ]]; then
  echo "usage: $0 N SUITE DIR [quasiroll bench options]   (N: number of shards >= 1)" >&2
  exit 2
fi
count=$1
suite=$(realpath "$2")
dir=$(realpath -m "$3")
shift 3
here=$(cd "$(dirname "$0")" && pwd)
quasiroll=$(realpath "${QUASIROLL:-$here/../../build/bench/quasiroll}")
[ -x "$quasiroll" ] || { echo "error: no quasiroll binary at $quasiroll (set QUASIROLL)" >&2; exit 2; }
[ -f "$suite" ] || { echo "error: no suite file $suite" >&2; exit 2; }
mkdir -p "$dir"
# shellcheck disable=SC2086  # QUASIROLL_SBATCH_ARGS is a list of options
array=$(sbatch --parsable ${QUASIROLL_SBATCH_ARGS:-} --array=0-$((count - 1)) \
  --export=ALL,QUASIROLL="$quasiroll",QUASIROLL_SHARD_COUNT="$count" \
  "$here/bench-array.sbatch" "$suite" "$dir" "$@")
array_id=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${QUASIROLL_SBATCH_ARGS:-} --dependency=afterok:"$array_id" \
  --kill-on-invalid-dep=yes --export=ALL,QUASIROLL="$quasiroll" \
  "$here/merge.sbatch" "$dir")
echo "submitted: array job $array_id ($count shards of $suite into $dir)," \
  "merge job ${merge%%;*} (runs after all shards succeed)"
