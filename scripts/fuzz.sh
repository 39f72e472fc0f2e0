#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang and
# -fsanitize=fuzzer,address,undefined in build-fuzz/ (or in a build given
# with --build) and runs each one for a bounded time (docs/fuzzing.md).
#   scripts/fuzz.sh [--build DIR] [SECONDS] [TARGET...]
#                                 default 60 s each, both targets
# --build DIR: an existing QUASIROLL_FUZZ=ON build to reuse (scripts/test.sh
# --sanitize makes build-asan one); only the targets are built there.
# The committed seed corpus (tests/fuzz/corpus/<target>) is read, never
# written; new inputs go to <build>/corpus/<target>, crashes to
# <build>/artifacts/<target>/. Exits 1 if any target found a crash.
# Needs clang and libclang-rt-14-dev (scripts/install-deps.sh --fuzz).
set -euo pipefail
cd "$(dirname "$0")/.."
build=build-fuzz
reuse=
if [ "${1:-}" = --build ]; then
  build=${2:?fuzz.sh: --build needs a directory}
  reuse=1
  shift 2
fi
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(fuzz_scene fuzz_quasi_static)
jobs=$(nproc 2>/dev/null || echo 2)
command -v clang++ > /dev/null || { echo "fuzz.sh: clang++ not found (scripts/install-deps.sh --fuzz)" >&2; exit 2; }

# ccache when present, as scripts/test.sh: the instrumented build is most of
# the step's time (docs/fuzzing.md). Its settings also for a reused build,
# whose launcher is ccache when test.sh found it.
export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=true
if [ -n "$reuse" ]; then
  grep -q '^QUASIROLL_FUZZ:BOOL=ON' "$build/CMakeCache.txt" 2> /dev/null \
    || { echo "fuzz.sh: $build is not a QUASIROLL_FUZZ=ON build" >&2; exit 2; }
else
  launcher=()
  command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Only what the targets need: no optional solver backends, tests, benchmarks.
  cmake -S . -B "$build" "${launcher[@]}" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DQUASIROLL_FUZZ=ON -DBUILD_TESTING=OFF -DQUASIROLL_WITH_BENCHMARKS=OFF \
    -DQUASIROLL_WITH_IPOPT=OFF -DQUASIROLL_WITH_NLOPT=OFF \
    -DQUASIROLL_WITH_CERES=OFF -DQUASIROLL_WITH_SUNDIALS=OFF > "$build.configure.log" \
    || { cat "$build.configure.log"; exit 1; }
  rm -f "$build.configure.log"
fi
cmake --build "$build" -j "$jobs" --target "${targets[@]}"

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t" "$build/artifacts/$t"
  args=(-max_total_time="$seconds" -timeout=20 -rss_limit_mb=2048
        -print_final_stats=1 -artifact_prefix="$build/artifacts/$t/")
  case "$t" in
    fuzz_scene) args+=(-max_len=8192 -dict=tests/fuzz/scene.dict) ;;
    fuzz_quasi_static) args+=(-max_len=1024) ;;
  esac
  echo "== $t: ${seconds}s"
  if "$build/tests/fuzz/$t" "${args[@]}" "$build/corpus/$t" "tests/fuzz/corpus/$t" \
      > "$build/$t.log" 2>&1; then
    grep -E '^(#[0-9]+ +DONE|stat::number_of_executed_units|stat::peak_rss_mb)' "$build/$t.log" || true
    grep -E '^#[0-9]+' "$build/$t.log" | tail -1
  else
    status=1
    echo "fuzz.sh: $t FAILED (log: $build/$t.log, artifacts: $build/artifacts/$t/)" >&2
    grep -E 'ERROR|runtime error|fuzz_scene:|fuzz_quasi_static:|Test unit written' "$build/$t.log" | head -20 >&2
  fi
done
exit $status
