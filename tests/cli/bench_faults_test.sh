#!/usr/bin/env bash
# quasiroll bench survives faults (issue #23 item 5; docs/harness.md, Faults).
#   tests/cli/bench_faults_test.sh QUASIROLL_BINARY kill|writers|disk
# kill     SIGKILL mid-way: --resume recomputes exactly the runs without a
#          finished runs/<id>.csv and ends with the output of an uninterrupted
#          run (scripts/compare-bench-outputs.py: runs.csv but its timing and
#          host columns, meta.json but its invocation keys, trajectories).
#          Held before the output lock and the disk fixes (atomic per-run
#          files, runs.csv rebuilt in grid order); this test keeps it so.
# writers  two processes on one output directory: the second exits 2 naming
#          the directory and the first one's pid, and the first one's output
#          is intact; shards of one suite still share a directory, while a
#          second process of the same shard, or a whole suite beside a shard,
#          is refused. Fails without bench/io/output_lock (both would run).
# disk     a full disk (a small tmpfs in a private mount namespace): the error
#          names the file and the system's reason, the exit code is 3, no
#          partial file is left and no run without all its files counted as
#          done; --resume after the space is freed completes the suite to the
#          uninterrupted output. Exits 77 (skipped) where no tmpfs can be
#          mounted (neither root nor unprivileged user namespaces) or pages
#          are not 4 KiB.
# Processes are frozen with SIGSTOP at the moment of interest instead of
# timed, so the test does not depend on the machine's speed or load.
set -euo pipefail
bin=$(realpath "$1")
mode=$2
cd "$(dirname "$0")/../.."
suite=tests/data/suites/faults.yaml
runs=12  # runs of $suite
args=(bench --suite "$suite" --jobs 1 --progress none)
compare=(/usr/bin/python3 scripts/compare-bench-outputs.py)
fail() {
  echo "bench faults ($mode): $*" >&2
  exit 1
}
# Finished runs: runs/<id>.csv (a temporary file is <id>.csv.tmp.<pid>.<n>).
finished() { find "$1/runs" -maxdepth 1 -name '*.csv' 2> /dev/null | wc -l; }
at_least() { [ "$(finished "$1")" -ge "$2" ]; }
# Waits until the command $2... succeeds, polling; fails naming $1 after 60 s.
wait_for() {
  local what=$1
  shift
  for _ in $(seq 3000); do
    "$@" && return 0
    sleep 0.02
  done
  fail "timed out waiting for $what"
}
# "(S selected, E executed, R resumed)" of a bench summary line.
summary() { grep -oE '\([0-9]+ selected, [0-9]+ executed, [0-9]+ resumed\)' <<< "$1"; }
expect_refused() {  # expect_refused DIR PID OUT: a bench on OUT exits 2 naming DIR and PID
  local code=0 err
  err=$("$bin" "${args[@]}" --out "$3" "${@:4}" 2>&1 > /dev/null) || code=$?
  [ "$code" -eq 2 ] || fail "a second writer of $1 exited $code, expected 2: $err"
  grep -qF "'$1'" <<< "$err" || fail "the error does not name $1: $err"
  grep -qF "process $2" <<< "$err" || fail "the error does not name pid $2: $err"
}

# full_disk SIZE WHAT: the suite on a fresh tmpfs of SIZE at $disk exits 3
# naming a file under $disk/out/WHAT and ENOSPC, and leaves no temporary file.
full_disk() {
  mount -t tmpfs -o size="$1" quasiroll_faults "$disk"
  local code=0 err
  err=$("$bin" "${args[@]}" --out "$disk/out" 2>&1 > /dev/null) || code=$?
  [ "$code" -eq 3 ] || fail "a full disk ($1) exited $code, expected 3: $err"
  grep -q "cannot write '$disk/out/${2:-}.*No space left on device" <<< "$err" \
    || fail "the error does not name a file under $disk/out/${2:-} and ENOSPC: $err"
  [ -z "$(find "$disk/out" -name '*.tmp.*')" ] \
    || fail "temporary files left: $(find "$disk/out" -name '*.tmp.*')"
}

if [ "$mode" = disk-inner ]; then  # in the private mount namespace
  whole=$3 disk=$4
  # 64 KiB: meta.json and the terrain fit, the 79 KB reference does not.
  full_disk 64k references/
  [ "$(finished "$disk/out")" -eq 0 ] || fail "runs done without their reference"
  umount "$disk"
  # 160 KiB: the reference and a few runs fit.
  full_disk 160k
  done_runs=$(finished "$disk/out")
  [ "$done_runs" -ge 1 ] && [ "$done_runs" -lt $runs ] \
    || fail "$done_runs runs done on the full disk, expected 1..$((runs - 1))"
  [ ! -e "$disk/out/runs.csv" ] || fail "runs.csv written on a full disk"
  grep -q '"complete":false' "$disk/out/meta.json" || fail "meta.json says complete"
  header=$(head -1 "$whole/runs.csv")
  for f in "$disk/out"/runs/*.csv; do  # a finished run: header, one row, all files
    id=$(basename "$f" .csv)
    [ "$(head -1 "$f")" = "$header" ] && [ "$(wc -l < "$f")" -eq 2 ] \
      && [ "$(tail -1 "$f" | cut -d, -f1)" = "$id" ] || fail "torn $f"
    cmp -s "$disk/out/trajectories/$id.csv" "$whole/trajectories/$id.csv" \
      || fail "the trajectory of the finished run $id differs"
  done
  mount -o remount,size=4m "$disk"
  out=$("$bin" "${args[@]}" --out "$disk/out" --resume 2>&1) || fail "resume failed: $out"
  [ "$(summary "$out")" = "($runs selected, $((runs - done_runs)) executed, $done_runs resumed)" ] \
    || fail "resume after freeing space: $out (expected $done_runs resumed)"
  "${compare[@]}" "$whole" "$disk/out" || fail "resumed output differs from an uninterrupted one"
  echo "bench faults (disk): no reference on 64 KiB -> exit 3, nothing done; 160 KiB -> exit 3 after $done_runs runs, resumed to the uninterrupted output"
  exit 0
fi

tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -KILL "$p" 2> /dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT
"$bin" "${args[@]}" --out "$tmp/whole" > /dev/null 2>&1 || fail "the uninterrupted run failed"

case "$mode" in
  kill)
    "$bin" "${args[@]}" --out "$tmp/killed" > /dev/null 2>&1 &
    pid=$!
    pids+=("$pid")
    wait_for "3 finished runs" at_least "$tmp/killed" 3
    kill -STOP "$pid"  # what the kill leaves is what is on disk now
    [ ! -e "$tmp/killed/runs.csv" ] || fail "the suite ended before the kill; lengthen $suite"
    done_runs=$(finished "$tmp/killed")
    kill -KILL "$pid"
    wait "$pid" 2> /dev/null || true
    grep -q '"complete":false' "$tmp/killed/meta.json" || fail "meta.json says complete"
    out=$("$bin" "${args[@]}" --out "$tmp/killed" --resume 2>&1) || fail "resume failed: $out"
    [ "$(summary "$out")" = "($runs selected, $((runs - done_runs)) executed, $done_runs resumed)" ] \
      || fail "killed after $done_runs runs, resume said: $out"
    "${compare[@]}" "$tmp/whole" "$tmp/killed" || fail "resumed output differs from an uninterrupted one"
    echo "bench faults (kill): SIGKILL after $done_runs of $runs runs; --resume executed the other $((runs - done_runs)), output identical"
    ;;
  writers)
    # The same suite twice into one directory, the first one frozen while
    # it holds the directory (meta.json is written after the lock is taken).
    "$bin" "${args[@]}" --out "$tmp/two" > /dev/null 2>&1 &
    pid=$!
    pids+=("$pid")
    wait_for "the first writer's meta.json" test -e "$tmp/two/meta.json"
    kill -STOP "$pid"
    expect_refused "$tmp/two" "$pid" "$tmp/two"
    expect_refused "$tmp/two" "$pid" "$tmp/two" --resume
    expect_refused "$tmp/two" "$pid" "$tmp/two" --shard 1/2
    kill -CONT "$pid"
    wait "$pid" || fail "the first writer failed"
    "${compare[@]}" "$tmp/whole" "$tmp/two" || fail "the first writer's output was disturbed"
    # Shards share DIR: shard 1/2 runs beside a frozen shard 0/2; a second
    # shard 0/2 is refused.
    "$bin" "${args[@]}" --out "$tmp/shared" --shard 0/2 > /dev/null 2>&1 &
    pid=$!
    pids+=("$pid")
    wait_for "shard 0's meta.json" test -e "$tmp/shared/shards/0-of-2/meta.json"
    kill -STOP "$pid"
    "$bin" "${args[@]}" --out "$tmp/shared" --shard 1/2 > /dev/null 2>&1 \
      || fail "shard 1/2 refused beside shard 0/2"
    expect_refused "$tmp/shared/shards/0-of-2" "$pid" "$tmp/shared" --shard 0/2
    kill -CONT "$pid"
    wait "$pid" || fail "shard 0/2 failed"
    "$bin" merge "$tmp/shared" --out "$tmp/shared" > /dev/null 2>&1 || fail "merge failed"
    "${compare[@]}" "$tmp/whole" "$tmp/shared" || fail "the merged shards differ from one process"
    echo "bench faults (writers): second writers refused with exit 2 naming the directory and pid; two shards shared a directory"
    ;;
  disk)
    mkdir "$tmp/disk"
    # The sizes below count 4 KiB pages (tmpfs allocates whole pages).
    if [ "$(getconf PAGESIZE)" -ne 4096 ]; then
      echo "bench faults (disk): skipped, page size $(getconf PAGESIZE), the sizes assume 4096"
      exit 77
    fi
    as_root=()
    [ "$(id -u)" -eq 0 ] || as_root=(-r)  # an unprivileged user namespace
    if ! unshare -m "${as_root[@]}" true 2> /dev/null; then
      echo "bench faults (disk): skipped, no private mount namespace (unshare -m${as_root[*]})"
      exit 77
    fi
    if ! unshare -m "${as_root[@]}" mount -t tmpfs -o size=64k none "$tmp/disk" 2> /dev/null; then
      echo "bench faults (disk): skipped, tmpfs cannot be mounted here"
      exit 77
    fi
    unshare -m "${as_root[@]}" bash "$0" "$bin" disk-inner "$tmp/whole" "$tmp/disk"
    ;;
  *) fail "unknown mode, expected kill|writers|disk" ;;
esac
