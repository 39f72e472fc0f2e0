#!/usr/bin/env bash
# quasiroll-mpi atlas (docs/cluster.md, "Atlas over MPI"):
#   1. mpirun -np 2 equals the one-process atlas REFERENCE except wall_s
#      (compare_atlas.py: atlas.csv and edge.csv), as does -np 1;
#   2. a worker rank killed with SIGKILL mid-way (test hook
#      QUASIROLL_TEST_MPI_KILL=1:40: rank 1 raises SIGKILL after its 40th
#      row): the job exits non-zero, rank 0 reports how many cells are
#      missing and the first ones, and no atlas.csv is written; a rerun with
#      --resume computes exactly the reported missing cells and equals
#      REFERENCE;
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

# 2. Rank 1 of 3 dies after 40 rows (chunks of 4 cells: mid-chunk).
set +e
QUASIROLL_TEST_MPI_KILL=1:40 mpi 3 atlas --spec "$spec" --out killed \
  --progress none --chunk 4 > /dev/null 2> killed.log
code=$?
set -e
[ "$code" != 0 ] || fail "a dead rank exited 0"
line=$(grep "cells missing (first: " killed.log) || { cat killed.log; fail "no missing-cells report"; }
missing=$(echo "$line" | sed -E 's/.*: ([0-9]+) of [0-9]+ cells missing.*/\1/')
[ "$missing" -gt 0 ] || fail "reported $missing missing cells"
[ ! -f killed/atlas.csv ] || fail "atlas.csv written after a rank died"
[ "$(wc -l < killed/atlas.partial.rank-1.csv)" = 40 ] || fail "rank 1's 40 rows are not on disk"
mpi 2 atlas --spec "$spec" --out killed --resume --progress none 2> resume.log
grep -q "resume: $((cells - missing)) of $cells cells already done" resume.log ||
  { cat killed.log resume.log; fail "resume did not find the reported finished cells"; }
grep -q "($missing computed, $((cells - missing)) kept)" resume.log ||
  { cat resume.log; fail "resume computed other than the $missing missing cells"; }
"${compare[@]}" "$reference" killed || fail "resumed atlas differs from one process"
ls killed/atlas.partial* > /dev/null 2>&1 && fail "partial files left behind"

# 3.
set +e
mpi 2 atlas --spec no-such-spec.yaml --out bad 2> bad.log
code=$?
set -e
[ "$code" = 2 ] || { cat bad.log; fail "bad spec: exit $code, expected 2"; }
[ "$(grep -c '^error: ' bad.log)" = 1 ] || { cat bad.log; fail "error not reported once"; }
echo "atlas_mpi_test: OK (rank 1 killed at 40 rows: $missing of $cells cells missing, resumed)"
