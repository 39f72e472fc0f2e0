#!/usr/bin/env bash
# The installed package works without the source tree (issue #17):
# `cmake --install` into a temporary prefix, then — with the source and build
# directories hidden behind empty bind mounts (a private mount namespace;
# without one: run from elsewhere and check that no file of the prefix names
# them) — pose, solve, run, bench, report (with --out/--strict passed
# through, and a clear exit 4 without matplotlib) and `import quasiroll`.
#   tests/cli/installed_prefix_test.sh BUILD_DIR [--python] [--sanitized]
# (--python: the build has the Python module, which must import;
# --sanitized: a sanitizer build, whose programs name source files by design
# (debug info, ASan's global descriptors), so the no-tree-path check is left
# to the Release build.)
set -euo pipefail
build=$(cd "$1" && pwd)
python=
sanitized=
for arg in "${@:2}"; do
  case "$arg" in
    --python) python=--python ;;
    --sanitized) sanitized=1 ;;
    "") ;;  # an empty generator expression
    *) echo "usage: $0 BUILD_DIR [--python] [--sanitized]" >&2; exit 2 ;;
  esac
done
src=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/quasiroll-installed.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" > "$tmp/install.log"
echo "installed-prefix: $(grep -c -E 'Installing|Up-to-date' "$tmp/install.log") files into $prefix"

# The installed programs and data hold no path into the source or build tree.
if [ -z "$sanitized" ] && grep -rlF -e "$src/" -e "$build/" "$prefix/bin" "$prefix/share/quasiroll" \
     $(find "$prefix" -name '_quasiroll*.so') > "$tmp/refs"; then
  echo "FAIL: installed files name the source/build tree: $(cat "$tmp/refs")"
  exit 1
fi

# The user's side: a work directory elsewhere, scenes and suites from the
# prefix, and a python without matplotlib for the error path.
work=$tmp/work
mkdir -p "$work" "$tmp/empty"
cat > "$tmp/python-without-site" <<SH
#!/bin/sh
exec /usr/bin/python3 -S "\$@"
SH
chmod +x "$tmp/python-without-site"
pypath=$(dirname "$(find "$prefix" -path '*/quasiroll/__init__.py' | head -n 1)")/..
[ "$python" != --python ] || [ -n "$(find "$prefix" -name '_quasiroll*.so')" ] ||
  { echo "FAIL: no Python module installed"; exit 1; }
cat > "$tmp/checks.sh" <<SH
set -euo pipefail
cd "$work"
q=$prefix/bin/quasiroll
data=$prefix/share/quasiroll
\$q --version | grep -q '^nlp .*newton'
\$q pose --scene \$data/bench/scenes/flat.yaml --json > pose.json
\$q solve --scene \$data/bench/scenes/incline10.yaml --json > solve.json
\$q run --scene \$data/bench/scenes/paper.yaml --t-end 1 --out run > /dev/null 2>&1
\$q bench --suite \$data/bench/suites/smoke.yaml --out bench --filter 'newton' --jobs 2 --progress none > /dev/null 2> bench.log
\$q report bench > report.log 2>&1
\$q report bench --out custom_report > report_out.log 2>&1
set +e
\$q report bench --out strict_report --strict > report_strict.log 2>&1
echo \$? > report_strict.rc
QUASIROLL_PYTHON=$tmp/python-without-site \$q report bench --out no_mpl > no_mpl.out 2> no_mpl.err
echo \$? > no_mpl.rc
set -e
[ "$python" = --python ] || exit 0
PYTHONPATH=$pypath /usr/bin/python3 -c "
import quasiroll
s = quasiroll.load_scene('\$data/bench/scenes/flat.yaml')
traj, stats = quasiroll.run(s, t_end=1)
assert stats['status'] == 'success' and len(traj) == 21, stats
print('python ok', quasiroll.backends()['nlp'])
" > python.log
SH
if unshare -m true 2> /dev/null; then
  hidden=yes
  unshare -m bash -c "mount --bind '$tmp/empty' '$build' && mount --bind '$tmp/empty' '$src' &&
                      [ -z \"\$(ls -A '$src')\" ] && bash '$tmp/checks.sh'"
else
  hidden="no (no mount namespace; checked that no installed file names it)"
  bash "$tmp/checks.sh"
fi

fail=0
check() { if eval "$2"; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi; }
check "pose --json" "grep -q '\"H_norm\"' '$work/pose.json'"
check "solve --json" "grep -q '\"status\":\"OK\"' '$work/solve.json'"
check "run" "[ \$(wc -l < '$work/run/trajectory.csv') -eq 22 ] && grep -q '\"status\":\"success\"' '$work/run/run.json'"
check "bench" "grep -q '40 runs (8 selected' '$work/bench.log' && [ -f '$work/bench/runs.csv' ]"
check "report" "[ -f '$work/bench/report/index.html' ] && [ \"\$(tail -n 1 '$work/report.log')\" = '$work/bench/report/index.html' ]"
check "report --out passed through" "[ -f '$work/custom_report/index.html' ] && [ ! -e '$work/custom_report/report' ]"
# A newton-only smoke suite leaves some figures without data: a placeholder
# by default (exit 0 above), an error with --strict.
check "report --strict passed through" "[ \$(cat '$work/report_strict.rc') -eq 2 ] && grep -q '^make_report: ' '$work/report_strict.log'"
check "report without matplotlib: exit 4" "[ \$(cat '$work/no_mpl.rc') -eq 4 ] && grep -q 'needs Python 3 with matplotlib' '$work/no_mpl.err' && grep -q 'QUASIROLL_PYTHON' '$work/no_mpl.err'"
[ "$python" != --python ] || check "import quasiroll" "grep -q 'python ok' '$work/python.log'"
echo "installed-prefix: source tree hidden: $hidden"
exit $fail
