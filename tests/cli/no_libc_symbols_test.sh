#!/usr/bin/env bash
# A library must not replace C library functions for the programs that link
# it (issue #17): no global symbol defined by a quasiroll library is also
# defined by the C library (libc.so.6 / libm.so.6). The getrusage of
# bench/cli/ipopt_timer_elision.cc is the CLI executable's own opt-in: the
# executable must define it (else Ipopt's task timers are back in the CLI).
#   tests/cli/no_libc_symbols_test.sh EXECUTABLE LIBRARY...
set -u
exe=$1
shift
fail=0
libc=$(ldd "$exe" | awk '$1 ~ /^libc\.so/ {print $3}')
libm=$(ldd "$exe" | awk '$1 ~ /^libm\.so/ {print $3}')
[ -f "$libc" ] || { echo "FAIL: cannot locate libc of $exe"; exit 1; }
libc_symbols=$(nm -D --defined-only "$libc" $libm | awk '{print $3}' | sed 's/@.*//' | sort -u)
for lib in "$@"; do
  # Global text/data symbols the archive defines (C linkage: unmangled).
  defined=$(nm --defined-only --extern-only "$lib" 2>/dev/null |
            awk 'NF == 3 && $2 ~ /^[TDBRVW]$/ {print $3}' | sort -u)
  clash=$(comm -12 <(echo "$libc_symbols") <(echo "$defined"))
  if [ -n "$clash" ]; then
    echo "FAIL: $(basename "$lib") defines C library symbols: $(echo $clash)"
    fail=1
  else
    echo "ok: $(basename "$lib") defines no C library symbol ($(echo "$defined" | grep -c .) global symbols checked)"
  fi
done
if nm --defined-only "$exe" | grep -qE ' T getrusage$'; then
  echo "ok: $(basename "$exe") defines its own getrusage (Ipopt timer elision)"
else
  echo "FAIL: $(basename "$exe") does not define getrusage: the CLI lost the Ipopt timer elision"
  fail=1
fi
# Through the CLI, with Ipopt: the elision changes no result (the same
# trajectory with QUASIROLL_IPOPT_TASK_TIMERS=1, Ipopt's real timers).
if "$exe" list | grep -q '^  ipopt '; then
  tmp=$(mktemp -d "${TMPDIR:-/tmp}/quasiroll-timers.XXXXXX")
  scene=$(dirname "$0")/../../bench/scenes/paper.yaml
  "$exe" run --scene "$scene" --nlp ipopt --t-end 2 --out "$tmp/elided" > /dev/null 2>&1
  QUASIROLL_IPOPT_TASK_TIMERS=1 "$exe" run --scene "$scene" --nlp ipopt --t-end 2 \
    --out "$tmp/timed" > /dev/null 2>&1
  if [ -s "$tmp/elided/trajectory.csv" ] &&
     cmp -s "$tmp/elided/trajectory.csv" "$tmp/timed/trajectory.csv"; then
    echo "ok: ipopt run identical with and without Ipopt's task timers"
  else
    echo "FAIL: ipopt run differs with QUASIROLL_IPOPT_TASK_TIMERS=1"
    fail=1
  fi
  rm -rf "$tmp"
fi
exit $fail
