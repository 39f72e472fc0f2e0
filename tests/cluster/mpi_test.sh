#!/usr/bin/env bash
# quasiroll-mpi end to end (docs/cluster.md):
#   1. mpirun -np NP quasiroll-mpi bench SUITE equals the --jobs 1 run
#      REFERENCE (scripts/compare-bench-outputs.py), and the dispatching
#      rank 0 does not spin while it waits (CPU / wall of its waits, from
#      DIR/mpi.json, below 10 %; a busy-polling wait is ~100 %);
#   with --extra (the smoke suite):
#   2. an idle worker (3 ranks, one run) does not spin either;
#   3. failing and throwing runs are rows; --resume; -np 1; bad input exits 2.
# usage: mpi_test.sh QUASIROLL_MPI SUITE NP REFERENCE WORKDIR [--extra]
set -euo pipefail
quasiroll_mpi=$1 suite=$2 np=$3 reference=$4 work=$5 extra=${6:-}
source "$(dirname "$0")/lib.sh"
compare=(/usr/bin/python3 "$root/scripts/compare-bench-outputs.py")
fresh_workdir "$work"

# Every rank that waited >= 1 s in total: idle CPU / idle wall < 10 %.
not_spinning() {  # DIR
  /usr/bin/python3 - "$1" <<'PY' || fail "a rank spins while idle ($1/mpi.json)"
import json, sys
ok = True
for r in json.load(open(sys.argv[1] + "/mpi.json"))["ranks"]:
    if r["idle_wall_s"] < 1:
        continue
    ratio = r["idle_cpu_s"] / r["idle_wall_s"]
    print("mpi_test: rank %d idle %.2f s wall, %.3f s CPU (%.2f %%)" %
          (r["rank"], r["idle_wall_s"], r["idle_cpu_s"], 100 * ratio))
    ok = ok and ratio < 0.1
sys.exit(0 if ok else 1)
PY
}
# status DIR RUN_ID_PREFIX: the status column of the first such row.
status() {
  /usr/bin/python3 -c "
import csv, sys
for r in csv.DictReader(open('$1/runs.csv')):
    if r['run_id'].startswith('$2'):
        print(r['status']); break"
}

# 1.
mpi "$np" bench --suite "$suite" --out out --progress none
"${compare[@]}" "$reference" out
grep -q "\"mpi\":{\"ranks\":$np}" out/meta.json || fail "meta.json lacks mpi.ranks"
not_spinning out
[ "$extra" = --extra ] || { echo "mpi_test: OK"; exit 0; }

# 2. One run, three ranks: rank 2 has nothing to do for the whole run.
mpi 3 bench --suite "$suite" --out idle --progress none \
  --filter 'coupled-paper-ipopt-ida'
not_spinning idle
[ "$(grep -c '"idle_wall_s"' idle/mpi.json)" -ge 1 ] || fail "no rank statistics"

# 3. Failures are rows; resume; -np 1; bad input.
cat > tiny.yaml <<YAML
name: tiny
scenes:
  - {name: paper, file: $root/bench/scenes/paper.yaml, overrides: {time: {t_end: 0.5}}}
groups:
  ok:
    nlp: [newton, ceres]
    dae: [rk-projection, ida]
  unstable:             # sigma * dt = 10 > 2.785: blows up
    dae: rk-baumgarte
    sigma: 200
  rough:                # no initial configuration: an "error" row
    roughness: 100
YAML
mpi 2 bench --suite tiny.yaml --out tiny --progress lines 2> tiny.log
[ "$(status tiny rough-)" = error ] || fail "no error row for the throwing run"
unstable=$(status tiny unstable-)
[ -n "$unstable" ] && [ "$unstable" != success ] || fail "unstable run: '$unstable'"
[ "$(status tiny ok-)" = success ] || fail "ok run did not succeed"
rm "tiny/runs/$(grep -m1 -o '^ok-[^,]*' tiny/runs.csv).csv"
mpi 2 bench --suite tiny.yaml --out tiny --resume --progress none 2> resume.log
grep -q "1 executed, 5 resumed" resume.log || { cat resume.log; fail "resume"; }
"$quasiroll_mpi" bench --suite tiny.yaml --out single --progress none  # -np 1
"${compare[@]}" single tiny
set +e
mpi 2 bench --suite tiny.yaml --out bad --filter '([' 2> bad.log
code=$?
set -e
[ "$code" = 2 ] || { cat bad.log; fail "bad --filter: exit $code, expected 2"; }
[ "$(grep -c 'error: --filter' bad.log)" = 1 ] || { cat bad.log; fail "error not reported once"; }
echo "mpi_test: OK"
