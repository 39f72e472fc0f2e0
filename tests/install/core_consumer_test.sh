#!/usr/bin/env bash
# find_package(quasiroll COMPONENTS core) against an installed prefix works
# without any solver or integrator package: installs BUILD_DIR into a
# temporary prefix, then configures tests/install/core_consumer with every
# solver/integrator package disabled (CMAKE_DISABLE_FIND_PACKAGE_<name>: a
# find_dependency() on one of them would fail the configure) and runs it;
# checks that the installed headers include each other as
# "quasiroll/<dir>/x.h", so only include/ needs to be on the include path.
#   tests/install/core_consumer_test.sh BUILD_DIR [--sanitized]
# (--sanitized: BUILD_DIR is a -fsanitize=address,undefined build, whose
# instrumented libraries need the sanitizer runtimes at link time.)
# The consumer is compiled by the build's own compiler: sanitizer runtimes
# (and the fuzz build's coverage hooks) are the compiler's.
set -euo pipefail
build=$(cd "$1" && pwd)
compiler=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
sanitize_flags=()
if [ "${2:-}" = --sanitized ]; then
  sanitize_flags=(-DCMAKE_CXX_FLAGS=-fsanitize=address,undefined
                  -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=address,undefined)
fi
src=$(cd "$(dirname "$0")/../.." && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/quasiroll-core-consumer.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
# Installed headers include each other as "quasiroll/<dir>/x.h" only.
if grep -rnE '^#include "(core|solvers|integrators|bench)/' "$tmp/prefix/include"; then
  echo "FAIL: installed headers with includes relative to include/quasiroll"
  exit 1
fi
disable=()
for pkg in Ceres SUNDIALS NLopt PkgConfig LAPACK BLAS Threads; do
  disable+=("-DCMAKE_DISABLE_FIND_PACKAGE_$pkg=ON")
done
cmake -S "$src/tests/install/core_consumer" -B "$tmp/build" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$tmp/prefix" "${disable[@]}" \
  ${compiler:+-DCMAKE_CXX_COMPILER="$compiler"} \
  "${sanitize_flags[@]}" \
  > "$tmp/configure.log" || { cat "$tmp/configure.log"; exit 1; }
grep 'core consumer' "$tmp/configure.log"
cmake --build "$tmp/build" > "$tmp/build.log" || { cat "$tmp/build.log"; exit 1; }
"$tmp/build/core_consumer"
