#!/usr/bin/env bash
# Installs every Debian package quasiroll needs. Idempotent; safe to re-run.
#   scripts/install-deps.sh          what the build and scripts/test.sh need
#   scripts/install-deps.sh --fuzz   also the optional fuzzing toolchain
set -euo pipefail
PACKAGES=(
  build-essential cmake pkg-config git ccache
  libeigen3-dev libbenchmark-dev libgtest-dev libgmock-dev libyaml-cpp-dev
  libcli11-dev python3 python3-matplotlib python3-numpy
  libopenmpi-dev openmpi-bin python3-pandas
  python3-dev pybind11-dev python3-pybind11 python3-pytest
  chromium clang-format libjs-three
)
# The optional backends' libraries: one line per quasiroll_add_backend()
# OPTION (solvers/CMakeLists.txt, integrators/CMakeLists.txt), with the
# backends that need them (docs/plugins.md, "Adding a backend").
BACKEND_PACKAGES=(
  coinor-libipopt-dev liblapack-dev  # QUASIROLL_WITH_IPOPT: ipopt, ipopt-mumps
  libnlopt-cxx-dev                   # QUASIROLL_WITH_NLOPT: slsqp
  libceres-dev                       # QUASIROLL_WITH_CERES: ceres
  libsundials-dev                    # QUASIROLL_WITH_SUNDIALS: ida, cvode-projection
)
PACKAGES+=("${BACKEND_PACKAGES[@]}")
# Optional, not needed by scripts/test.sh: clang + libFuzzer runtime for
# scripts/fuzz.sh (docs/fuzzing.md).
OPTIONAL_FUZZ_PACKAGES=(clang libclang-rt-14-dev)
for arg in "$@"; do
  case "$arg" in
    --fuzz) PACKAGES+=("${OPTIONAL_FUZZ_PACKAGES[@]}") ;;
    *) echo "usage: $0 [--fuzz]" >&2; exit 2 ;;
  esac
done
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
