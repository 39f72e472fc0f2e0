#!/usr/bin/env bash
# Builds quasiroll and runs the whole test suite (ctest).
#   scripts/test.sh              Release build in build/, warnings as errors
#   scripts/test.sh --sanitize   clang with -fsanitize=address,undefined in
#                                build-asan/, which also builds the libFuzzer
#                                targets (scripts/fuzz.sh --build build-asan)
# Installs the Debian dependencies first (scripts/install-deps.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
sanitize=OFF
build_dir=build
for arg in "$@"; do
  case "$arg" in
    --sanitize) sanitize=ON; build_dir=build-asan ;;
    *) echo "usage: $0 [--sanitize]" >&2; exit 2 ;;
  esac
done
if [ "$sanitize" = ON ]; then bash scripts/install-deps.sh --fuzz; else bash scripts/install-deps.sh; fi
jobs=$(nproc 2>/dev/null || echo 2)
build_type=Release
sanitizer_config=()
# The sanitizer pass with clang: it compiles this code about twice as fast
# as GCC (core/quasi_static.cc under ASan: 72 s against 155 s at -O2 -g,
# 51 s at -O1 with line tables only), and the same instrumented objects
# (QUASIROLL_FUZZ adds libFuzzer's coverage) serve the fuzz targets, so a
# clean CI machine compiles the library twice instead of three times.
if [ "$sanitize" = ON ]; then
  build_type=RelWithDebInfo
  # (The micro-benchmarks are no test: the Release build has them.)
  sanitizer_config=(-DCMAKE_CXX_COMPILER=clang++ -DQUASIROLL_FUZZ=ON
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -gline-tables-only -DNDEBUG"
    -DQUASIROLL_WITH_BENCHMARKS=OFF)
fi
# The minutes-long tests (label long: the default suite through Slurm shards
# and MPI, docs/cluster.md) in the Release build only.
long_tests=ON
[ "$sanitize" = ON ] && long_tests=OFF
# ccache (installed by install-deps.sh) when present: paths relative to the
# checkout (CCACHE_BASEDIR, no hashed working directory) so that another
# clone of the same sources on this machine reuses the objects.
launcher=()
if command -v ccache > /dev/null; then
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=true
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B "$build_dir" "${launcher[@]}" -DCMAKE_BUILD_TYPE="$build_type" \
  -DQUASIROLL_WERROR=ON -DQUASIROLL_SANITIZE="$sanitize" \
  -DQUASIROLL_LONG_TESTS="$long_tests" "${sanitizer_config[@]}"
cmake --build "$build_dir" -j "$jobs"
# The sanitizer pass leaves the tests of tests/sanitizer-skip.txt (minutes
# each under ASan, their units covered by shorter tests) to the Release pass.
skip=()
if [ "$sanitize" = ON ]; then
  skipped=$(sed -e 's/#.*//' -e 's/[[:space:]]*$//' -e '/^$/d' tests/sanitizer-skip.txt)
  names=$(printf '%s\n' "$skipped" | sed -e 's/[.[\*^$()+?{|]/\\&/g' | paste -sd '|')
  # (a parameterised gtest's ctest name ends in "  # GetParam() = ...")
  skip=(-E "^($names)( +# GetParam.*)?\$")
  # A name that is no test any more (renamed, removed) is an error, not a
  # silent no-op.
  listed=$(ctest --test-dir "$build_dir" -N | sed -n 's/^ *Test *#[0-9]*: //p' \
    | sed 's/  *# GetParam.*//')
  stale=$(printf '%s\n' "$skipped" | grep -vxF -f <(printf '%s\n' "$listed") || true)
  if [ -n "$stale" ]; then
    echo "test.sh: tests/sanitizer-skip.txt names no test: $stale" >&2
    exit 1
  fi
fi
ctest --test-dir "$build_dir" --output-on-failure -j "$jobs" "${skip[@]}"
