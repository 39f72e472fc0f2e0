#!/usr/bin/env bash
# The Slurm job-array path end to end with a faked Slurm (tests/cluster/
# fake-slurm: sbatch runs array tasks as local processes with the SLURM_*
# variables Slurm sets; srun logs its options):
#   1. scripts/slurm/submit.sh N SUITE DIR: N shard tasks, then the merge job
#      (afterok); DIR equals the --jobs 1 run REFERENCE (compare-bench-outputs);
#   2. a resubmitted task (QUASIROLL_SHARD_COUNT, --array=1) resumes, and a
#      second merge gives the same result;
#   3. a failing array (bad --filter) never runs the merge;
#   4. the array script refuses to run outside an array / on an array that
#      does not start at 0.
# usage: slurm_test.sh QUASIROLL SUITE N REFERENCE WORKDIR
set -euo pipefail
quasiroll=$1 suite=$2 shards=$3 reference=$4 work=$5
source "$(dirname "$0")/lib.sh"
compare=(/usr/bin/python3 "$root/scripts/compare-bench-outputs.py")
fresh_workdir "$work"
fake_slurm "$quasiroll"

# 1. Array + merge.
bash "$root/scripts/slurm/submit.sh" "$shards" "$suite" "$work/out"
array=$(sed -n 1p slurm/submitted)
merge=$(sed -n 2p slurm/submitted)
[ "$(cat "slurm/$array.status")" = ok ] || { cat slurm/"${array}"_*.out; fail "array job"; }
[ "$(cat "slurm/$merge.status")" = ok ] || { cat "slurm/$merge.out"; fail "merge job"; }
for ((i = 0; i < shards; i++)); do
  grep -q "shard $i/$shards of .* on $(hostname)" "slurm/${array}_$i.out" ||
    fail "task $i log lacks its shard and host"
  [ -f "out/shards/$i-of-$shards/meta.json" ] || fail "shard $i wrote no meta.json"
done
[ "$(grep -c -- '--cpu-bind=cores' slurm/srun.log)" -eq "$shards" ] ||
  fail "tasks not launched through srun --cpu-bind=cores"
"${compare[@]}" "$reference" out

# 2. Lose a run of shard 1, resubmit that task alone, merge again.
lost=$(sed -n 2p "out/shards/1-of-$shards/runs.csv" | cut -d, -f1)
[ -n "$lost" ] || fail "shard 1 has no run"
rm "out/runs/$lost.csv" "out/runs.csv"
QUASIROLL_SHARD_COUNT=$shards sbatch --array=1 --export=ALL \
  "$root/scripts/slurm/bench-array.sbatch" "$suite" "$work/out" > /dev/null
resubmitted=$(tail -n 1 slurm/submitted)
[ "$(cat "slurm/$resubmitted.status")" = ok ] || fail "resubmitted task"
grep -q "^resume: " "slurm/${resubmitted}_1.out" || fail "the task did not resume"
grep -q "1 executed" "slurm/${resubmitted}_1.out" || fail "the task re-ran more than the lost run"
sbatch "$root/scripts/slurm/merge.sbatch" "$work/out" > /dev/null
[ "$(cat "slurm/$(tail -n 1 slurm/submitted).status")" = ok ] || fail "second merge"
"${compare[@]}" "$reference" out

# 3. A failing array: the merge never runs.
bash "$root/scripts/slurm/submit.sh" 2 "$suite" "$work/bad" --filter '(['
[ "$(cat "slurm/$(tail -n 2 slurm/submitted | head -n 1).status")" = failed ] ||
  fail "bad --filter did not fail the array"
[ "$(cat "slurm/$(tail -n 1 slurm/submitted).status")" = dependency_never_satisfied ] ||
  fail "merge ran after a failed array"
[ ! -f bad/runs.csv ] || fail "merge wrote runs.csv after a failed array"

# 4. Outside an array / an array not starting at 0.
if (unset SLURM_ARRAY_TASK_ID; bash "$root/scripts/slurm/bench-array.sbatch" "$suite" x) 2> err.txt; then
  fail "ran outside a job array"
fi
grep -q "SLURM_ARRAY_TASK_ID is not set" err.txt || fail "unclear error outside an array"
if SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_MIN=1 SLURM_ARRAY_TASK_MAX=4 SLURM_ARRAY_TASK_COUNT=4 \
  bash "$root/scripts/slurm/bench-array.sbatch" "$suite" x 2> err.txt; then
  fail "ran on an array 1-4 without QUASIROLL_SHARD_COUNT"
fi
grep -q "QUASIROLL_SHARD_COUNT" err.txt || fail "unclear error for an array 1-4"
echo "slurm_test: OK ($shards shards of $(basename "$suite"))"
