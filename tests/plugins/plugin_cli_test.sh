#!/usr/bin/env bash
# A backend from a plugin library runs through the standard tools with no
# edit anywhere else: listed, run in a suite (with its BackendInfo in
# meta.json), planned for shards, reported; a library that is not a plugin,
# a missing file and a name clash each get one clear line and exit 2.
#   plugin_cli_test.sh QUASIROLL PLUGIN NOT_A_PLUGIN CLASHING [QUASIROLL_MPI]
set -euo pipefail
cli=$1 plugin=$2 not_plugin=$3 clashing=$4 mpi=${5:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# Listed, with the plugin's BackendInfo.
"$cli" --plugin "$plugin" list --json > "$tmp/list.json"
grep -q '"levenberg-marquardt"' "$tmp/list.json" || fail "list: no levenberg-marquardt"
grep -q '"midpoint-projection"' "$tmp/list.json" || fail "list: no midpoint-projection"
QUASIROLL_PLUGIN_PATH="$plugin" "$cli" list | grep -q levenberg-marquardt ||
  fail "QUASIROLL_PLUGIN_PATH not honoured"

# A suite naming only plugin backends; --plugin after the command works too.
sed "s|SCENE_FILE|$PWD/bench/scenes/paper.yaml|" tests/plugins/plugin_suite.yaml \
  > "$tmp/suite.yaml"
"$cli" bench --plugin "$plugin" --suite "$tmp/suite.yaml" --out "$tmp/plan" --plan > "$tmp/plan.csv"
[ "$(wc -l < "$tmp/plan.csv")" = 3 ] || fail "plan: expected 2 runs: $(cat "$tmp/plan.csv")"
"$cli" --plugin "$plugin" bench --suite "$tmp/suite.yaml" --out "$tmp/out" --jobs 2 \
  > "$tmp/bench.log" 2>&1 || fail "bench: $(cat "$tmp/bench.log")"
/usr/bin/python3 - "$tmp/out" "$plugin" <<'PY'
import csv, hashlib, json, os, sys
out, plugin = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(os.path.join(out, "runs.csv"))))
assert len(rows) == 2, rows
for r in rows:
    assert r["nlp"] == "levenberg-marquardt" and r["dae"] == "midpoint-projection", r
    assert r["status"] == "success", (r["run_id"], r["status"], r["stop_reason"])
meta = json.load(open(os.path.join(out, "meta.json")))
(p,) = meta["plugins"]
assert p["sha256"] == hashlib.sha256(open(plugin, "rb").read()).hexdigest(), p
assert p["version"] == "0.1.0" and p["nlp"] == ["levenberg-marquardt"], p
assert p["dae"] == ["midpoint-projection"], p
assert "--plugin" in meta["command"], meta["command"]
names = [b["name"] for b in meta["backends"]["nlp"]]
assert "levenberg-marquardt" in names, names
info = [b for b in meta["backends"]["dae"] if b["name"] == "midpoint-projection"][0]
assert info["family"] == "explicit Runge-Kutta", info
PY
"$cli" report "$tmp/out" --out "$tmp/report" > "$tmp/report.log" 2>&1 ||
  fail "report: $(tail -5 "$tmp/report.log")"
[ -s "$tmp/report/index.html" ] || fail "report: no index.html"
grep -q levenberg-marquardt "$tmp/report/index.html" || fail "report does not name the plugin backend"

# Through MPI as well (same plugin on every rank), if built.
if [ -n "$mpi" ] && command -v mpirun > /dev/null; then
  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    mpirun --oversubscribe -np 2 "$mpi" bench --plugin "$plugin" \
    --suite "$tmp/suite.yaml" --out "$tmp/mpi" --progress none > "$tmp/mpi.log" 2>&1 ||
    fail "quasiroll-mpi: $(tail -5 "$tmp/mpi.log")"
  /usr/bin/python3 "$PWD/scripts/compare-bench-outputs.py" "$tmp/out" "$tmp/mpi" ||
    fail "quasiroll-mpi results differ from quasiroll's"
fi

# Clear errors, exit 2, one line naming the file.
expect_error() {  # expect_error PATTERN ARGS...
  local pattern=$1; shift
  set +e
  "$cli" "$@" list > "$tmp/out.txt" 2> "$tmp/err.txt"
  local code=$?
  set -e
  [ "$code" = 2 ] || fail "$*: exit $code, expected 2"
  [ "$(wc -l < "$tmp/err.txt")" = 1 ] || fail "$*: expected one line: $(cat "$tmp/err.txt")"
  grep -q -- "$pattern" "$tmp/err.txt" || fail "$*: '$(cat "$tmp/err.txt")' lacks '$pattern'"
}
expect_error "not a quasiroll plugin" --plugin "$not_plugin"
expect_error "$(basename "$not_plugin")" --plugin "$not_plugin"
expect_error "no such file" --plugin "$tmp/missing.so"
expect_error "is registered already" --plugin "$clashing"
expect_error "cannot be loaded" --plugin "$tmp/suite.yaml"
echo "plugin_cli_test: passed"
