#!/usr/bin/env bash
# Fails if any tracked C++ file differs from .clang-format (Google base).
#   scripts/check-format.sh        check;   scripts/check-format.sh --fix   apply
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.cc' '*.h')
if [ "${1:-}" = "--fix" ]; then
  clang-format -i "${files[@]}"
  exit 0
fi
clang-format --dry-run -Werror "${files[@]}"
echo "check-format: ${#files[@]} files formatted"
