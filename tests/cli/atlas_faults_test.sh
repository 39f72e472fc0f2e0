#!/usr/bin/env bash
# quasiroll atlas survives faults (issue #23 item 5): a run killed with
# SIGKILL mid-way resumes from the rows it had finished and ends with the
# atlas.csv of an uninterrupted run (all but wall_s); a write failure names
# the file and exits non-zero without a complete-looking atlas.csv; a second
# process on the same directory is refused.
#   tests/cli/atlas_faults_test.sh QUASIROLL_BINARY
set -euo pipefail
bin=$1
cd "$(dirname "$0")/../.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
args=(atlas --scene bench/scenes/paper.yaml --x -1 3 6 --y -1 1 5 --headings 4
      --progress none --jobs 1)
strip() { cut -d, -f1-15 "$1"; }  # every column but wall_s

"$bin" "${args[@]}" --out "$tmp/whole" > /dev/null

# SIGKILL once 40 of the 240 rows are on disk.
"$bin" "${args[@]}" --out "$tmp/killed" > /dev/null &
pid=$!
for _ in $(seq 600); do
  rows=$( { cat "$tmp/killed/atlas.partial.csv" 2> /dev/null || true; } | wc -l)
  [ "$rows" -ge 40 ] && break
  sleep 0.05
done
kill -9 "$pid"
wait "$pid" 2> /dev/null || true
[ ! -f "$tmp/killed/atlas.csv" ] || { echo "atlas.csv exists after a kill"; exit 1; }
kept=$(wc -l < "$tmp/killed/atlas.partial.csv")
out=$("$bin" "${args[@]}" --out "$tmp/killed" --resume)
echo "$out" | grep -q "kept" || { echo "no summary: $out"; exit 1; }
reused=$(echo "$out" | sed -E 's/.*computed, ([0-9]+) kept.*/\1/')
[ "$reused" -ge 40 ] || { echo "resume kept $reused rows, expected >= 40 ($kept on disk)"; exit 1; }
diff <(strip "$tmp/whole/atlas.csv") <(strip "$tmp/killed/atlas.csv") \
  || { echo "resumed atlas differs from an uninterrupted one"; exit 1; }
[ ! -f "$tmp/killed/atlas.partial.csv" ] || { echo "partial file left behind"; exit 1; }

# A full disk, emulated by /dev/full as the partial file: the error names
# the path, the exit code is not 0, and no atlas.csv is written.
mkdir -p "$tmp/full"
ln -s /dev/full "$tmp/full/atlas.partial.csv"
set +e
err=$("$bin" "${args[@]}" --out "$tmp/full" 2>&1 > /dev/null)
code=$?
set -e
[ "$code" -ne 0 ] || { echo "a write failure exited 0"; exit 1; }
echo "$err" | grep -q "atlas.partial.csv" || { echo "error does not name the file: $err"; exit 1; }
[ ! -f "$tmp/full/atlas.csv" ] || { echo "atlas.csv written after a write failure"; exit 1; }
# Two writers on one directory: the second one, started while the first is
# frozen (SIGSTOP) holding it, exits 2 naming the directory and the first
# one's pid (bench/io/output_lock.h); the first one's atlas is intact.
"$bin" "${args[@]}" --out "$tmp/two" > /dev/null &
pid=$!
for _ in $(seq 3000); do
  [ -e "$tmp/two/meta.json" ] && break  # written after the lock is taken
  sleep 0.02
done
kill -STOP "$pid"
set +e
err=$("$bin" "${args[@]}" --out "$tmp/two" --resume 2>&1 > /dev/null)
code=$?
set -e
kill -CONT "$pid"
[ "$code" -eq 2 ] || { echo "a second writer exited $code, expected 2: $err"; exit 1; }
echo "$err" | grep -qF "'$tmp/two'" || { echo "error does not name the directory: $err"; exit 1; }
echo "$err" | grep -qF "process $pid" || { echo "error does not name pid $pid: $err"; exit 1; }
wait "$pid" || { echo "the first writer failed"; exit 1; }
diff <(strip "$tmp/whole/atlas.csv") <(strip "$tmp/two/atlas.csv") \
  || { echo "the first writer's atlas was disturbed"; exit 1; }
echo "atlas faults: kill at $kept rows resumed to the uninterrupted atlas; full disk named; second writer refused"
