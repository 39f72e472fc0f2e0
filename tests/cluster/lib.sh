# Sourced by tests/cluster/*_test.sh: `root` (the checkout), `fail MSG`,
# `fresh_workdir DIR` (empty it and cd there), `fake_slurm QUASIROLL` (the
# faked sbatch and srun on PATH, state in ./slurm), `atlas_cells DIR` (the
# cell count of an atlas's meta.json), Open MPI settings for local ranks,
# `mpi NP ARGS...` (mpirun of $quasiroll_mpi), and `killed_job_missing WHAT
# CODE LOG` (a job whose rank died: non-zero CODE, LOG has rank 0's
# "N of M WHAT missing (first: ..." line; prints N > 0).
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
fail() { echo "$(basename "$0" .sh): FAIL: $*" >&2; exit 1; }
fresh_workdir() { rm -rf "$1" && mkdir -p "$1" && cd "$1"; }
fake_slurm() {
  export FAKE_SLURM_DIR=$PWD/slurm PATH=$root/tests/cluster/fake-slurm:$PATH
  export QUASIROLL=$1
}
atlas_cells() {
  /usr/bin/python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['cells'])" "$1/meta.json"
}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# No network interfaces needed between local ranks; keep Open MPI quiet.
export OMPI_MCA_btl=self,vader OMPI_MCA_btl_vader_single_copy_mechanism=none
mpi() { local n=$1; shift; mpirun -np "$n" --oversubscribe "$quasiroll_mpi" "$@"; }
killed_job_missing() {
  local what=$1 code=$2 log=$3 line n
  [ "$code" != 0 ] || fail "a dead rank exited 0"
  line=$(grep "$what missing (first: " "$log") || { cat "$log" >&2; fail "no missing-$what report"; }
  n=$(echo "$line" | sed -E "s/.*: ([0-9]+) of [0-9]+ $what missing.*/\1/")
  [ "$n" -gt 0 ] || fail "reported $n missing $what"
  echo "$n"
}
