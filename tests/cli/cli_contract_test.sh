#!/usr/bin/env bash
# The CLI contract of docs/cli.md, one check per promise (issue #17):
# outputs checked before any work, no 0 sentinels, progress, SIGINT
# (run: partial trajectory + INTERRUPTED; bench: --resume), empty --filter,
# --version, unknown-flag hints, --jobs range, one name per concept with
# deprecated spellings, flag names in errors, null for unknown values, one
# "no wheel" convention, and every flag of every command documented.
#   tests/cli/cli_contract_test.sh QUASIROLL_BINARY
set -u
bin=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
cd "$(dirname "$0")/../.."
src=$PWD
py=/usr/bin/python3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/quasiroll-cli.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL $*"; fail=$((fail + 1)); }
flat=$src/bench/scenes/flat.yaml
incline=$src/bench/scenes/incline10.yaml

# expect_error NAME CODE TEXT COMMAND...: exit CODE, one stderr line with TEXT.
expect_error() {
  local name=$1 code=$2 text=$3
  shift 3
  local err rc
  err=$(timeout 60 "$@" 2>&1 >/dev/null)
  rc=$?
  if [ "$rc" -ne "$code" ]; then bad "$name: exit $rc (want $code): $err"; return; fi
  if [ "$(printf '%s' "$err" | grep -c '')" -ne 1 ]; then bad "$name: not one line: $err"; return; fi
  case "$err" in *"$text"*) ok ;; *) bad "$name: lacks '$text': $err" ;; esac
}
json() {  # json FILE PYTHON-EXPRESSION-ON-d  -> prints the value
  "$py" -c 'import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$1" "$2"
}

# --- outputs are checked before any work ---------------------------------
# (a 10^6 s run would take hours: a check after the simulation times out)
mkdir "$tmp/cwd" && cd "$tmp/cwd"
expect_error "run --out ''" 2 "--out: must name a directory" "$bin" run --scene "$flat" --t-end 100000 --out ''
[ -z "$(ls -A "$tmp/cwd")" ] && ok || bad "run --out '' wrote into the working directory"
touch "$tmp/a_file"
expect_error "run --out FILE" 2 "--out: exists and is not a directory" "$bin" run --scene "$flat" --t-end 100000 --out "$tmp/a_file"
expect_error "run --out FILE/sub" 2 "--out: cannot be created" "$bin" run --scene "$flat" --t-end 100000 --out "$tmp/a_file/sub"
expect_error "bench --out ''" 2 "--out: must name a directory" "$bin" bench --suite "$src/bench/suites/default.yaml" --out ''
expect_error "bench --out FILE" 2 "--out: exists and is not a directory" "$bin" bench --suite "$src/bench/suites/default.yaml" --out "$tmp/a_file"
cd "$src"

# --- no 0 sentinels: 0 is an error naming the flag -------------------------
for flag in --mu --dt --t-end --eps --tol --atol --nlp-tol; do
  expect_error "run $flag 0" 2 "$flag: must be a finite number > 0, got '0'" "$bin" run --scene "$flat" $flag 0 --out "$tmp/r0"
done
expect_error "solve --mu 0" 2 "--mu: must be a finite number > 0" "$bin" solve --scene "$flat" --mu 0
expect_error "run --dt abc" 2 "--dt: must be a finite number > 0, got 'abc'" "$bin" run --scene "$flat" --dt abc
[ ! -e "$tmp/r0" ] && ok || bad "a rejected run created its --out"
# Left out, the scene's values are used.
"$bin" run --scene "$flat" --out "$tmp/scene_values" > /dev/null 2>&1
[ "$(json "$tmp/scene_values/run.json" 'd["options"]["dt"], d["options"]["t_end"], d["scene"]["mu"]')" = "(0.05, 20, 0.5)" ] && ok || bad "defaults are not the scene's: $(json "$tmp/scene_values/run.json" 'd["options"]')"

# --- errors name the flag the user typed -----------------------------------
err=$("$bin" run --scene "$flat" --dae rk-baumgarte --sigma -1 2>&1 >/dev/null)
case "$err" in *"--sigma: must be a finite number >= 0"*) ok ;; *) bad "--sigma -1: $err" ;; esac
case "$err" in *integrator.*|*baumgarte_sigma*) bad "--sigma -1 names an internal key: $err" ;; *) ok ;; esac
expect_error "--rk rk9 names --rk" 2 "--rk: must be one of rk4, dp54, bs32, got 'rk9'" "$bin" run --scene "$flat" --rk rk9
expect_error "--dt > --t-end" 2 "--dt: must be <= the end time 1 s (--t-end), got 5" "$bin" run --scene "$flat" --dt 5 --t-end 1
expect_error "--dt > scene t_end" 2 "--dt: must be <= the end time 20 s (scene time.t_end)" "$bin" run --scene "$flat" --dt 50
expect_error "--dae-index 3" 2 "--dae-index: must be an integer in [1, 2], got '3'" "$bin" run --scene "$flat" --dae-index 3

# --- unknown flags and commands: in the order typed, with a hint -----------
expect_error "typo flag" 2 "--rk-metod: unknown option of 'quasiroll run' (did you mean --rk-method?)" "$bin" run --scene "$flat" --rk-metod rk4 --zzz
expect_error "first unknown flag first" 2 "--foo: unknown option" "$bin" run --scene "$flat" --foo --bar
expect_error "typo command" 2 "unknown command 'rn' (did you mean run?)" "$bin" rn --scene "$flat"
expect_error "stray argument" 2 "unexpected argument 'xyz'" "$bin" pose --scene "$flat" xyz
expect_error "no command" 2 "a command is required" "$bin"

# --- --jobs is validated, with a short message -----------------------------
for jobs in -1 0 1025 99999999999999999999999999 2.5 abc; do
  expect_error "--jobs $jobs" 2 "--jobs: must be an integer in [1, 1024], got '$jobs'" "$bin" bench --suite "$src/tests/data/suites/cli_contract.yaml" --out "$tmp/jobs" --jobs "$jobs"
done

# --- one name per concept; old spellings with a deprecation note ------------
err=$("$bin" run --scene "$flat" --t-end 1 --dae rk-projection --rk dp54 --rtol 1e-6 --out "$tmp/old" 2>&1 >/dev/null)
case "$err" in *"note: --rk is deprecated, use --rk-method"*) ok ;; *) bad "no --rk note: $err" ;; esac
case "$err" in *"note: --rtol is deprecated, use --tol"*) ok ;; *) bad "no --rtol note: $err" ;; esac
[ "$(json "$tmp/old/run.json" 'd["options"]["rk_method"], d["options"]["rtol"]')" = "('dp54', 1e-06)" ] && ok || bad "old spellings not applied"
"$bin" run --scene "$flat" --t-end 1 --rk-method dp54 --tol 1e-6 --nlp-tol 1e-11 --eps 1e-7 --substeps 2 --out "$tmp/new" > /dev/null 2>&1
[ "$(json "$tmp/new/run.json" 'd["options"]["rk_method"], d["options"]["rtol"], d["options"]["nlp_residual_tolerance"], d["scene"]["epsilon"], d["options"]["step"]')" = "('dp54', 1e-06, 1e-11, 1e-07, 0.025)" ] && ok || bad "new names not applied: $(json "$tmp/new/run.json" 'd["options"]')"
# --sigma / --dae-index are integrator options of ida (shorthands of --dae-opt).
"$bin" run --scene "$flat" --t-end 1 --dae ida --sigma 2 --dae-index 1 --out "$tmp/new_ida" > /dev/null 2>&1
[ "$(json "$tmp/new_ida/run.json" 'd["options"]["sigma"], d["options"]["dae_index"], d["options"]["dae_options"]["used"]["baumgarte_sigma"]')" = "(2, 1, 2)" ] && ok || bad "--sigma/--dae-index not applied: $(json "$tmp/new_ida/run.json" 'd["options"]')"
expect_error "both spellings" 2 "excludes" "$bin" run --scene "$flat" --rk dp54 --rk-method rk4
# Every concept flag of `run` is a suite group key with '_' -> '-'.
for key in rk_method tol sigma dae_index nlp_tol eps mu dt t_end substeps contact_check; do
  grep -q "^| \`$key\` |" docs/harness.md && ok || bad "suite key $key not in docs/harness.md"
  "$bin" run --help | grep -q -- "--${key//_/-} " && ok || bad "no flag --${key//_/-}"
done

# --- --version ----------------------------------------------------------------
v=$("$bin" --version)
grep -Eq '^commit +([0-9a-f]{12}(-dirty)?|unknown)$' <<< "$v" && ok || bad "--version: no commit: $v"
grep -Eq '^build type +[A-Za-z]+' <<< "$v" && ok || bad "--version: no build type: $v"
grep -Eq '^nlp .*newton' <<< "$v" && ok || bad "--version: no NLP backends: $v"
grep -Eq '^dae .*rk-projection' <<< "$v" && ok || bad "--version: no integrators: $v"

# --- run: progress on a terminal, not in a pipe --------------------------------
"$bin" run --scene "$flat" --t-end 2 --out "$tmp/p1" 2> "$tmp/p1.err" > /dev/null
grep -q $'\r' "$tmp/p1.err" && bad "progress line written to a non-terminal" || ok
"$bin" run --scene "$flat" --t-end 2 --out "$tmp/p2" --progress bar 2> "$tmp/p2.err" > /dev/null
grep -q $'\rrun: t = 2 / 2 s  100%  41 samples' "$tmp/p2.err" && ok || bad "--progress bar: $(od -c "$tmp/p2.err" | head -3)"
if command -v script > /dev/null; then
  script -qec "'$bin' run --scene '$flat' --t-end 2 --out '$tmp/p3'" /dev/null > "$tmp/p3.tty" 2>&1
  grep -q $'\rrun: t = 2 / 2 s' "$tmp/p3.tty" && ok || bad "no progress on a terminal: $(head -c 300 "$tmp/p3.tty")"
fi

# --- run: SIGINT keeps the trajectory so far ----------------------------------
"$bin" run --scene "$flat" --t-end 20000 --progress bar --out "$tmp/int" 2> "$tmp/int.err" > /dev/null &
pid=$!
for _ in $(seq 1 200); do grep -q 'samples' "$tmp/int.err" 2>/dev/null && break; sleep 0.05; done
sleep 0.3
kill -INT "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] && ok || bad "interrupted run: exit $rc (want 130)"
if [ -f "$tmp/int/run.json" ]; then
  [ "$(json "$tmp/int/run.json" 'd["status"]')" = INTERRUPTED ] && ok || bad "run.json status: $(json "$tmp/int/run.json" 'd["status"]')"
  rows=$(($(wc -l < "$tmp/int/trajectory.csv") - 1))
  [ "$rows" -gt 1 ] && [ "$rows" -eq "$(json "$tmp/int/run.json" 'd["samples"]')" ] && ok || bad "interrupted trajectory has $rows rows"
  [ "$(json "$tmp/int/run.json" 'd["t_reached"] > 0 and d["t_reached"] < 20000')" = True ] && ok || bad "t_reached"
else
  bad "interrupted run wrote no run.json"
fi

# --- bench: SIGINT names --resume, and --resume finishes the suite ----------
"$bin" bench --suite "$src/bench/suites/smoke.yaml" --out "$tmp/b" --jobs 1 --progress lines 2> "$tmp/b.err" > /dev/null &
pid=$!
for _ in $(seq 1 600); do [ "$(ls "$tmp/b/runs" 2>/dev/null | wc -l)" -ge 2 ] && break; sleep 0.05; done
kill -INT "$pid"
wait "$pid"
rc=$?
[ "$rc" -eq 130 ] && ok || bad "interrupted bench: exit $rc (want 130)"
grep -q -- "--resume" "$tmp/b.err" && ok || bad "interrupt message lacks --resume: $(tail -3 "$tmp/b.err")"
resume=$(grep -o 'quasiroll bench .*--resume.*' "$tmp/b.err" | head -n 1)
"$bin" ${resume#quasiroll } --progress none > /dev/null 2> "$tmp/b2.err"
grep -Eq '40 runs \(40 selected, [0-9]+ executed, [1-9][0-9]* resumed\)' "$tmp/b2.err" && ok || bad "resume after interrupt: $(cat "$tmp/b2.err")"

# --- bench: a filter that matches nothing is bad input -------------------------
expect_error "empty filter" 2 "--filter: matches none of the 2 run ids" "$bin" bench --suite "$src/tests/data/suites/cli_contract.yaml" --out "$tmp/f" --filter nomatch
[ ! -e "$tmp/f" ] && ok || bad "empty --filter created the output directory"

# --- null for unknown values; one "no wheel" convention -------------------------
"$bin" solve --scene "$incline" --mu 0.1 --json > "$tmp/solve_fail.json"
[ $? -eq 1 ] && ok || bad "failed solve: exit code"
[ "$(json "$tmp/solve_fail.json" '(d["twist"], d["joint_rates"], d["gap"], d["contacts"][0]["normal_force"], d["contacts"][1]["point"], d["critical_wheel"])')" = "([None, None, None, None, None, None], [None, None, None, None, None, None], None, None, [None, None, None], 2)" ] && ok || bad "failed solve --json: $(cat "$tmp/solve_fail.json")"
"$bin" solve --scene "$flat" --json > "$tmp/solve_ok.json"
[ "$(json "$tmp/solve_ok.json" 'd["critical_wheel"], d["contacts"][0]["normal_force"] > 24')" = "(None, True)" ] && ok || bad "ok solve --json: critical_wheel"
"$bin" run --scene "$incline" --mu 0.1 --out "$tmp/run_fail" > /dev/null 2>&1
[ $? -eq 1 ] && ok || bad "failed run: exit code"
[ "$(json "$tmp/run_fail/run.json" 'd["critical_wheel"]')" = 2 ] && ok || bad "run.json critical_wheel (failed)"
[ "$(json "$tmp/scene_values/run.json" 'd["critical_wheel"], d["mu_min_at_stop"]')" = "(None, None)" ] && ok || bad "run.json critical_wheel (success) not null"
"$bin" bench --suite "$src/tests/data/suites/cli_contract.yaml" --out "$tmp/wheel" --jobs 1 --progress none > /dev/null 2>&1
"$py" - "$tmp/wheel/runs.csv" <<'PY' && ok || bad "runs.csv critical_wheel"
import csv, sys
rows = {r["scene"]: r for r in csv.DictReader(open(sys.argv[1]))}
assert rows["flat"]["critical_wheel"] == "", rows["flat"]["critical_wheel"]
assert rows["incline_low_mu"]["critical_wheel"] == "2", rows["incline_low_mu"]["critical_wheel"]
PY

# --- every flag of every command is in docs/cli.md -----------------------------
for cmd in pose solve run list bench merge report; do
  for flag in $("$bin" $cmd --help | grep -oE '^ +(-[a-z],)?--[a-z][a-z0-9-]*' | grep -oE -- '--[a-z][a-z0-9-]*'); do
    [ "$flag" = --help ] && continue
    grep -q -- "\`$flag" docs/cli.md && ok || bad "docs/cli.md does not document '$cmd $flag'"
  done
  grep -q "^## \`quasiroll $cmd\`" docs/cli.md && ok || bad "docs/cli.md has no section for $cmd"
done
for code in 0 1 2 3 4 130; do
  grep -q "^| $code |" docs/cli.md && ok || bad "exit code $code not in docs/cli.md"
done

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
