#!/usr/bin/env bash
# quasiroll-mpi atlas (docs/cluster.md, "Atlas over MPI"):
#   1. mpirun -np 2 equals the one-process atlas REFERENCE except wall_s
#      (compare_atlas.py: atlas.csv and edge.csv), as does -np 1;
#   2. a worker rank killed with SIGKILL mid-way (test hook
#      QUASIROLL_TEST_MPI_KILL=1:42: rank 1 raises SIGKILL after its 42nd
#      row): the job exits non-zero, rank 0 reports how many cells are
#      missing and the first ones, rank 1's 42 rows are on disk and no
#      atlas.csv is written; a rerun with --resume computes at most the
#      reported missing cells (exactly those unless another rank was still
#      writing a row) and equals REFERENCE;
#   3. a bad spec exits 2 with the error reported once.
# usage: atlas_mpi_test.sh QUASIROLL_MPI SPEC REFERENCE WORKDIR
set -euo pipefail
quasiroll_mpi=$1 spec=$2 reference=$3 work=$4
source "$(dirname "$0")/lib.sh"
compare=(/usr/bin/python3 "$root/tests/cluster/compare_atlas.py")
fresh_workdir "$work"
cells=$(atlas_cells "$reference")

# 1.
mpi 2 atlas --spec "$spec" --out out --progress none 2> out.log
"${compare[@]}" "$reference" out || fail "-np 2 differs from one process"
grep -q '"mpi":{"ranks":2' out/meta.json || fail "meta.json lacks mpi.ranks"
"$quasiroll_mpi" atlas --spec "$spec" --out single --progress none 2> /dev/null
"${compare[@]}" "$reference" single || fail "-np 1 differs from one process"

# 2. Rank 1 of 3 dies after 42 rows (chunks of 4 cells: mid-chunk).
set +e
QUASIROLL_TEST_MPI_KILL=1:42 mpi 3 atlas --spec "$spec" --out killed \
  --progress none --chunk 4 > /dev/null 2> killed.log
code=$?
set -e
missing=$(killed_job_missing cells "$code" killed.log)
[ ! -f killed/atlas.csv ] || fail "atlas.csv written after a rank died"
[ "$(wc -l < killed/atlas.partial.rank-1.csv)" = 42 ] || fail "rank 1's 42 rows are not on disk"
mpi 2 atlas --spec "$spec" --out killed --resume --progress none 2> resume.log
# The report is what was on disk when rank 0 looked: resume computes those
# cells, or fewer if another rank was finishing a row at that moment.
computed=$(sed -nE 's/.*\(([0-9]+) computed, ([0-9]+) kept\).*/\1/p' resume.log)
kept=$(sed -nE 's/.*\(([0-9]+) computed, ([0-9]+) kept\).*/\2/p' resume.log)
[ -n "$computed" ] && [ "$computed" -gt 0 ] && [ "$computed" -le "$missing" ] &&
  [ $((computed + kept)) = "$cells" ] ||
  { cat killed.log resume.log; fail "resume computed $computed cells, $missing reported missing"; }
"${compare[@]}" "$reference" killed || fail "resumed atlas differs from one process"
ls killed/atlas.partial* > /dev/null 2>&1 && fail "partial files left behind"

# 3.
set +e
mpi 2 atlas --spec no-such-spec.yaml --out bad 2> bad.log
code=$?
set -e
[ "$code" = 2 ] || { cat bad.log; fail "bad spec: exit $code, expected 2"; }
[ "$(grep -c '^error: ' bad.log)" = 1 ] || { cat bad.log; fail "error not reported once"; }
echo "atlas_mpi_test: OK (rank 1 killed at 42 rows: $missing of $cells cells missing, resumed)"
