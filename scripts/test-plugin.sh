#!/usr/bin/env bash
# Installs quasiroll into a temporary prefix, builds the out-of-tree example
# plugin (examples/external_plugin) against the installed package and runs it
# and its conformance-kit test (plugin_conformance_test).
#   scripts/test-plugin.sh [BUILD_DIR] [-- plugin_demo args]
# BUILD_DIR defaults to build-pkg (configured and built here if missing, with
# tests and micro-benchmarks off). Exits non-zero on any failure.
set -euo pipefail
cd "$(dirname "$0")/.."
src=$PWD
build=build-pkg
if [ $# -gt 0 ] && [ "$1" != "--" ]; then build=$1; shift; fi
[ "${1:-}" = "--" ] && shift
jobs=$(nproc 2>/dev/null || echo 2)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DQUASIROLL_WERROR=ON \
    -DBUILD_TESTING=OFF -DQUASIROLL_WITH_BENCHMARKS=OFF
fi
cmake --build "$build" -j "$jobs"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/quasiroll-plugin.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
echo "test-plugin: installed into $tmp/prefix ($(grep -c Installing "$tmp/install.log") files)"
# The installed CLI runs from the prefix.
"$tmp/prefix/bin/quasiroll" list > /dev/null
cmake -S "$src/examples/external_plugin" -B "$tmp/build" \
  -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$tmp/prefix"
cmake --build "$tmp/build" -j "$jobs"
# A pinned build (QUASIROLL_REFERENCE_LAPACK, docs/performance.md) passes the
# pin on: the plugin's executable loads the reference BLAS and no ATLAS.
if grep -q '^QUASIROLL_REFERENCE_BLAS_DIR:PATH=/' "$build/CMakeCache.txt" &&
   grep -q '^QUASIROLL_REFERENCE_LAPACK:BOOL=ON' "$build/CMakeCache.txt"; then
  libs=$(ldd "$tmp/build/plugin_demo")
  if grep -E 'atlas|f77blas' <<< "$libs" ||
     ! grep -qE 'libblas\.so\.3 => /usr/lib/[^ ]*/blas/' <<< "$libs"; then
    echo "test-plugin: plugin_demo does not load the reference BLAS:" >&2
    echo "$libs" >&2
    exit 1
  fi
  echo "test-plugin: plugin_demo loads the reference BLAS and LAPACK, no ATLAS"
fi
"$tmp/build/plugin_demo" "$@"
# The plugins through the installed conformance kit (docs/plugins.md).
"$tmp/build/plugin_conformance_test"
# The loadable plugin through the installed `quasiroll --plugin`: a suite of
# its backends only, and the report of it.
plugin="$tmp/build/quasiroll_example_plugin.so"
sed "s|SCENE_FILE|$tmp/prefix/share/quasiroll/bench/scenes/paper.yaml|" \
  "$src/tests/plugins/plugin_suite.yaml" > "$tmp/plugin-suite.yaml"
"$tmp/prefix/bin/quasiroll" --plugin "$plugin" bench --suite "$tmp/plugin-suite.yaml" \
  --out "$tmp/plugin-out" --progress none
if [ "$(grep -c ',success,' "$tmp/plugin-out/runs.csv")" != 2 ]; then
  echo "test-plugin: the plugin suite did not succeed:" >&2
  cat "$tmp/plugin-out/runs.csv" >&2
  exit 1
fi
"$tmp/prefix/bin/quasiroll" report "$tmp/plugin-out" --out "$tmp/plugin-report" > /dev/null
grep -q levenberg-marquardt "$tmp/plugin-report/index.html"
echo "test-plugin: the loadable plugin ran a suite and a report through the installed quasiroll"
