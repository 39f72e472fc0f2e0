#!/usr/bin/env bash
# Builds quasiroll and runs the whole test suite (ctest).
#   scripts/test.sh              Release build in build/, warnings as errors
#   scripts/test.sh --sanitize   same with -fsanitize=address,undefined in build-asan/
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
bash scripts/install-deps.sh
jobs=$(nproc 2>/dev/null || echo 2)
build_type=Release
[ "$sanitize" = ON ] && build_type=RelWithDebInfo
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
  -DQUASIROLL_LONG_TESTS="$long_tests"
cmake --build "$build_dir" -j "$jobs"
ctest --test-dir "$build_dir" --output-on-failure -j "$jobs"
