#!/usr/bin/env bash
# quasiroll-mpi bench when a rank dies (issue #23 item 5; docs/cluster.md):
# worker rank 1 of 3 raises SIGKILL when given its 5th run, after 4 finished
# (test hook QUASIROLL_TEST_MPI_KILL=1:4), so that run is missing however fast
# rank 2 finishes the rest. The job exits non-zero, rank 0 reports how
# many runs are missing and the first ones, no runs.csv is written; a rerun
# with --resume executes at most the reported runs (exactly those unless a
# worker was still writing one when rank 0 looked) and its results equal
# the --jobs 1 REFERENCE (scripts/compare-bench-outputs.py). Without the
# report, before this test, mpirun ended the job with no word on what was
# left.
# usage: mpi_rank_death_test.sh QUASIROLL_MPI SUITE REFERENCE WORKDIR
set -euo pipefail
quasiroll_mpi=$1 suite=$2 reference=$3 work=$4
source "$(dirname "$0")/lib.sh"
fresh_workdir "$work"
set +e
QUASIROLL_TEST_MPI_KILL=1:4 mpi 3 bench --suite "$suite" --out killed \
  --progress none > /dev/null 2> killed.log
code=$?
set -e
missing=$(killed_job_missing runs "$code" killed.log)
[ ! -f killed/runs.csv ] || fail "runs.csv written after a rank died"
mpi 2 bench --suite "$suite" --out killed --resume --progress none 2> resume.log
executed=$(sed -nE 's/.*\(([0-9]+) selected, ([0-9]+) executed.*/\2/p' resume.log)
[ -n "$executed" ] || { cat resume.log; fail "no summary line after --resume"; }
[ "$executed" -le "$missing" ] || fail "--resume executed $executed runs, $missing were reported missing"
/usr/bin/python3 "$root/scripts/compare-bench-outputs.py" "$reference" killed \
  || fail "resumed results differ from --jobs 1"
echo "mpi_rank_death: $missing runs reported missing, $executed executed on --resume, results equal"
