#!/usr/bin/env bash
# Every malformed input is rejected with exit code 2 and ONE line on stderr
# naming the key (and value); never a signal or an uncaught exception.
#   tests/cli/bad_input_test.sh QUASIROLL_BINARY
# Corpus: tests/bad_scenes/*.yaml (scenes) and *.suite.yaml (suites), each
# with a first-line comment "# expect: <text the message must contain>".
set -u
bin=$1
cd "$(dirname "$0")/../.."
pass=0
fail=0
check() {  # check NAME EXPECTED_TEXT COMMAND...
  local name=$1 expect=$2
  shift 2
  local err rc lines
  err=$("$@" 2>&1 >/dev/null)
  rc=$?
  lines=$(printf '%s' "$err" | grep -c '')
  if [ "$rc" -ne 2 ]; then
    echo "FAIL $name: exit code $rc (want 2): $err"; fail=$((fail + 1)); return
  fi
  if [ "$lines" -ne 1 ]; then
    echo "FAIL $name: $lines lines on stderr (want 1): $err"; fail=$((fail + 1)); return
  fi
  case "$err" in
    *"$expect"*) pass=$((pass + 1)) ;;
    *) echo "FAIL $name: message lacks '$expect': $err"; fail=$((fail + 1)) ;;
  esac
}
for f in tests/bad_scenes/*.yaml; do
  expect=$(sed -n 's/^# expect: //p' "$f" | head -n 1)
  case "$f" in
    *.suite.yaml)  # suites are rejected before anything runs
      check "bench $(basename "$f")" "$expect" "$bin" bench --suite "$f" --out /tmp/quasiroll-bad-suite ;;
    *)
      check "pose $(basename "$f")" "$expect" "$bin" pose --scene "$f" ;;
  esac
done
# A few through the other subcommands, and bad command-line values.
check "run mu_nan" "mu" "$bin" run --scene tests/bad_scenes/mu_nan.yaml --out /tmp/quasiroll-bad-run
check "solve unknown key" "foo" "$bin" solve --scene tests/bad_scenes/unknown_top_key.yaml
check "missing file" "no_such_scene.yaml" "$bin" pose --scene tests/bad_scenes/no_such_scene.yaml
check "--mu negative" "--mu" "$bin" solve --scene bench/scenes/flat.yaml --mu -1
check "unknown nlp" "nope" "$bin" solve --scene bench/scenes/flat.yaml --nlp nope
check "unknown dae" "nope" "$bin" run --scene bench/scenes/flat.yaml --dae nope --out /tmp/quasiroll-bad-run
check "bad coupling" "coupling" "$bin" run --scene bench/scenes/flat.yaml --coupling sometimes
check "bad rk" "rk" "$bin" run --scene bench/scenes/flat.yaml --rk rk9 --out /tmp/quasiroll-bad-run
check "negative sigma" "sigma" "$bin" run --scene bench/scenes/flat.yaml --dae rk-baumgarte --sigma -1 --out /tmp/quasiroll-bad-run
check "dt > t_end" "dt" "$bin" run --scene bench/scenes/flat.yaml --dt 5 --t-end 1 --out /tmp/quasiroll-bad-run
# Backend options (--nlp-opt / --dae-opt): unknown or ill-typed -> exit 2
# naming the option and the known ones.
check "unknown dae option" "'no_such'" "$bin" run --scene bench/scenes/flat.yaml --dae-opt no_such=1 --out /tmp/quasiroll-bad-run
check "unknown dae option lists known" "known: projection_tolerance" "$bin" run --scene bench/scenes/flat.yaml --dae-opt no_such=1 --out /tmp/quasiroll-bad-run
check "dae option of another integrator" "'dae_index'" "$bin" run --scene bench/scenes/flat.yaml --dae rk-projection --dae-opt dae_index=1 --out /tmp/quasiroll-bad-run
check "ill-typed dae option" "max_projection_iterations" "$bin" run --scene bench/scenes/flat.yaml --dae-opt max_projection_iterations=two --out /tmp/quasiroll-bad-run
check "out-of-range nlp option" "armijo" "$bin" run --scene bench/scenes/flat.yaml --nlp-opt armijo=2 --out /tmp/quasiroll-bad-run
check "solve unknown nlp option" "'nope'" "$bin" solve --scene bench/scenes/flat.yaml --nlp-opt nope=1
check "option without =" "--dae-opt" "$bin" run --scene bench/scenes/flat.yaml --dae-opt rk_method --out /tmp/quasiroll-bad-run
check "option given twice" "given twice" "$bin" run --scene bench/scenes/flat.yaml --dae-opt rk_method=rk4 --dae-opt rk_method=dp54 --out /tmp/quasiroll-bad-run
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
