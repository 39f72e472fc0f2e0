#!/usr/bin/env bash
# A sharded atlas through a faked Slurm array (tests/cluster/fake-slurm) and
# quasiroll merge (docs/cluster.md, "Atlas"):
#   1. bench/atlases/atlas-array.sbatch as a 3-task array, then
#      scripts/slurm/merge.sbatch (afterok): DIR equals the one-process atlas
#      REFERENCE except wall_s (compare_atlas.py: atlas.csv and edge.csv);
#   2. a shard killed mid-way (its atlas.csv gone, 20 rows in its partial
#      file): merge exits 2 naming how many cells are missing and the first;
#      the task resubmitted alone computes only its missing cells, and the
#      merge then equals REFERENCE;
#   3. shards that disagree on the commit: merge exits 2 naming the key,
#      both files and both values;
#   4. a bad --shard exits 2 with one line naming --shard and the value,
#      writing nothing.
# usage: atlas_slurm_test.sh QUASIROLL SPEC REFERENCE WORKDIR
set -euo pipefail
quasiroll=$1 spec=$2 reference=$3 work=$4
source "$(dirname "$0")/lib.sh"
compare=(/usr/bin/python3 "$root/tests/cluster/compare_atlas.py")
fresh_workdir "$work"
fake_slurm "$quasiroll"
cells=$(atlas_cells "$reference")

# 1. Array + merge.
array=$(sbatch --parsable --array=0-2 "$root/bench/atlases/atlas-array.sbatch" "$spec" "$work/out")
merge=$(sbatch --parsable --dependency=afterok:"$array" "$root/scripts/slurm/merge.sbatch" "$work/out")
[ "$(cat "slurm/$array.status")" = ok ] || { cat slurm/"${array}"_*.out; fail "array job"; }
[ "$(cat "slurm/$merge.status")" = ok ] || { cat "slurm/$merge.out"; fail "merge job"; }
for i in 0 1 2; do
  [ -f "out/shards/$i-of-3/atlas.csv" ] || fail "shard $i wrote no atlas.csv"
  grep -q "\"shard\":{\"index\":$i,\"count\":3" "out/shards/$i-of-3/meta.json" ||
    fail "shard $i meta.json lacks its shard"
done
"${compare[@]}" "$reference" out || fail "merged atlas differs from one process"
grep -q '"merge":{"inputs":\[' out/meta.json || fail "merged meta.json lacks its inputs"

# 2. Shard 1 (cells [c/3, 2c/3)) killed after 20 rows: its rows so far are
# in its partial file, no atlas.csv.
first=$((cells / 3))
sed -n "2,21p" out/shards/1-of-3/atlas.csv > out/shards/1-of-3/atlas.partial.csv
rm out/shards/1-of-3/atlas.csv out/atlas.csv
set +e
"$quasiroll" merge out --out out 2> merge.err
code=$?
set -e
[ "$code" = 2 ] || { cat merge.err; fail "merge with a missing shard: exit $code, expected 2"; }
grep -q "$((cells / 3)) of $cells atlas cells have no row in the inputs (first: $first)" merge.err ||
  { cat merge.err; fail "merge does not name the missing cells"; }
QUASIROLL_SHARD_COUNT=3 sbatch --array=1 --export=ALL \
  "$root/bench/atlases/atlas-array.sbatch" "$spec" "$work/out" > /dev/null
task=$(tail -n 1 slurm/submitted)
[ "$(cat "slurm/$task.status")" = ok ] || { cat "slurm/${task}_1.out"; fail "resubmitted task"; }
grep -q "($((cells / 3 - 20)) computed, 20 kept)" "slurm/${task}_1.out" ||
  { cat "slurm/${task}_1.out"; fail "the task did not compute only its missing cells"; }
"$quasiroll" merge out --out out 2> /dev/null
"${compare[@]}" "$reference" out || fail "merge after resume differs from one process"

# 3. Another commit in one shard's meta.json.
mkdir -p other/shards
cp -r out/shards/0-of-3 other/shards/
sed -i 's/"commit":"[^"]*"/"commit":"0123456789ab"/' other/shards/0-of-3/meta.json
set +e
"$quasiroll" merge out other --out merged 2> disagree.err
code=$?
set -e
[ "$code" = 2 ] || { cat disagree.err; fail "disagreeing commits: exit $code"; }
grep -q 'inputs disagree on commit: .*out/shards/0-of-3/meta.json has ".*", .*other/shards/0-of-3/meta.json has "0123456789ab"' disagree.err ||
  { cat disagree.err; fail "disagreement not named"; }

# 4. Bad --shard.
for bad in 3/3 1/0 x -1/2; do
  set +e
  "$quasiroll" atlas --spec "$spec" --out bad --shard "$bad" > /dev/null 2> bad.err
  code=$?
  set -e
  [ "$code" = 2 ] || fail "--shard $bad: exit $code, expected 2"
  [ "$(wc -l < bad.err)" = 1 ] && grep -q -- "--shard.*$bad" bad.err ||
    { cat bad.err; fail "--shard $bad: not one line naming --shard and the value"; }
  [ ! -e bad ] || fail "--shard $bad wrote output"
done
echo "atlas_slurm_test: OK (3 shards of $cells cells, merged, resumed, merged)"
