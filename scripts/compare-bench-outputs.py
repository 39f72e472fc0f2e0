#!/usr/bin/python3
"""Checks that two `quasiroll bench` output directories hold the same results.

    /usr/bin/python3 scripts/compare-bench-outputs.py A B [--no-trajectories]

Compares (docs/cluster.md, "What is identical"):
  runs.csv   byte for byte after dropping the timing and host columns
             (wall_s, wall_s_median, wall_s_min, wall_s_max, wall_s_all,
             wall_per_sim_s, host, cpu_model, wall_s_q1, wall_s_q3,
             wall_s_iqr, timing_exclusive) from both;
  meta.json  key by key, in order, after dropping the invocation keys
             (machine, jobs, resume, options, shard, start_time, end_time,
             wall_s, runs_executed, runs_resumed, merge, mpi, command);
  trajectories/<run_id>.csv byte for byte for every row (unless
             --no-trajectories).
Exit 0 if identical, 1 with the first differences on stderr otherwise.

Golden outputs (a suite's results recorded once, e.g. before a refactoring
that must not change them; ctest bench_golden_smoke). Columns added to
runs.csv since (an additive change) are not compared:
    compare-bench-outputs.py --record-golden OUT GOLDEN   writes GOLDEN/runs.csv
        (timing and host columns dropped), GOLDEN/trajectories.sha256 and
        GOLDEN/trajectories.columns (the trajectory.csv header)
    compare-bench-outputs.py --golden GOLDEN OUT          compares OUT with them
Columns added to trajectory.csv since (at its end) are not compared either:
the digests are taken over the recorded columns (GOLDEN/trajectories.columns;
a golden without it was recorded before any was added: whole files).
"""
import hashlib
import csv
import io
import json
import os
import sys

TIMING_AND_HOST_COLUMNS = {"wall_s", "wall_s_median", "wall_s_min", "wall_s_max",
                           "wall_s_all", "wall_per_sim_s", "host", "cpu_model",
                           "wall_s_q1", "wall_s_q3", "wall_s_iqr", "timing_exclusive"}
INVOCATION_META_KEYS = {"machine", "jobs", "resume", "options", "shard", "start_time",
                        "end_time", "wall_s", "runs_executed", "runs_resumed", "merge", "mpi",
                        "command"}


def runs_without_timing(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    keep = [k for k, name in enumerate(rows[0]) if name not in TIMING_AND_HOST_COLUMNS]
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    for r in rows:
        w.writerow([r[k] for k in keep])
    return rows, out.getvalue().splitlines()


def meta_without_invocation(path):
    with open(path) as f:
        meta = json.load(f)
    return [(k, v) for k, v in meta.items() if k not in INVOCATION_META_KEYS]


def trajectory_text(path, columns=None):
    """A trajectory file's bytes, cut to `columns` (a header line) when given;
    trajectory.csv has no quoted fields, so the cut is exact."""
    with open(path, "rb") as f:
        data = f.read()
    if columns is None:
        return data
    lines = data.decode().split("\n")
    header = lines[0].split(",")
    names = columns.split(",")
    if header[:len(names)] == names:  # added columns sit at the end
        return "\n".join(",".join(line.split(",")[:len(names)]) if line else line
                         for line in lines).encode()
    keep = [header.index(n) for n in names]
    return "\n".join(",".join(line.split(",")[k] for k in keep) if line else line
                     for line in lines).encode()


def trajectory_digests(directory, rows, columns=None):
    lines = []
    for r in rows[1:]:
        name = os.path.join("trajectories", r[0] + ".csv")
        text = trajectory_text(os.path.join(directory, name), columns)
        lines.append(f"{hashlib.sha256(text).hexdigest()}  {name}")
    return lines


def trajectory_header(directory, rows):
    for r in rows[1:]:
        with open(os.path.join(directory, "trajectories", r[0] + ".csv")) as f:
            return f.readline().rstrip("\n")
    return None


def record_golden(out, golden):
    rows, stripped = runs_without_timing(os.path.join(out, "runs.csv"))
    os.makedirs(golden, exist_ok=True)
    with open(os.path.join(golden, "runs.csv"), "w") as f:
        f.write("\n".join(stripped) + "\n")
    with open(os.path.join(golden, "trajectories.sha256"), "w") as f:
        f.write("\n".join(trajectory_digests(out, rows)) + "\n")
    header = trajectory_header(out, rows)
    if header is not None:
        with open(os.path.join(golden, "trajectories.columns"), "w") as f:
            f.write(header + "\n")
    print(f"compare-bench-outputs: recorded {len(rows) - 1} rows of {out} in {golden}")
    return 0


def columns_of(lines, names):
    """The CSV `lines` cut to the columns `names` (in that order)."""
    rows = list(csv.reader(lines))
    keep = [rows[0].index(n) for n in names]
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    for r in rows:
        w.writerow([r[k] for k in keep])
    return out.getvalue().splitlines()


def compare_golden(golden, out):
    rows, stripped = runs_without_timing(os.path.join(out, "runs.csv"))
    with open(os.path.join(golden, "runs.csv")) as f:
        expected = f.read().splitlines()
    # runs.csv changes only additively: columns added since the golden was
    # recorded are not compared; every golden column must still be there.
    golden_columns = next(csv.reader(expected[:1]))
    missing = [c for c in golden_columns if c not in next(csv.reader(stripped[:1]))]
    if missing:
        print(f"compare-bench-outputs: runs.csv lost the columns {missing}", file=sys.stderr)
        return 1
    stripped = columns_of(stripped, golden_columns)
    with open(os.path.join(golden, "trajectories.sha256")) as f:
        expected_digests = f.read().splitlines()
    problems = []
    if expected[0] != stripped[0]:
        problems.append(f"runs.csv columns differ:\n  golden {expected[0]}\n  now    {stripped[0]}")
    elif len(expected) != len(stripped):
        problems.append(f"runs.csv: {len(expected) - 1} golden rows, {len(stripped) - 1} now")
    else:
        for k, (x, y) in enumerate(zip(expected, stripped)):
            if x != y:
                problems.append(f"runs.csv line {k + 1} differs:\n  golden {x}\n  now    {y}")
    columns_file = os.path.join(golden, "trajectories.columns")
    columns = None
    if os.path.exists(columns_file):
        with open(columns_file) as f:
            columns = f.read().strip()
    digests = trajectory_digests(out, rows, columns) if not problems else []
    for x, y in zip(expected_digests, digests):
        if x != y:
            problems.append(f"{y.split()[-1]} differs from the golden one")
    for p in problems[:10]:
        print(f"compare-bench-outputs: {p}", file=sys.stderr)
    if not problems:
        print(f"compare-bench-outputs: {out} equals the golden {golden} "
              f"({len(stripped) - 1} rows and their trajectories; timing/host columns aside)")
    return 1 if problems else 0


def main():
    if len(sys.argv) == 4 and sys.argv[1] in ("--record-golden", "--golden"):
        mode, x, y = sys.argv[1:]
        return record_golden(x, y) if mode == "--record-golden" else compare_golden(x, y)
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    trajectories = "--no-trajectories" not in sys.argv
    if len(args) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    a, b = args
    problems = []
    rows_a, ta = runs_without_timing(os.path.join(a, "runs.csv"))
    _, tb = runs_without_timing(os.path.join(b, "runs.csv"))
    if ta != tb:
        if len(ta) != len(tb):
            problems.append(f"runs.csv: {len(ta) - 1} rows in {a}, {len(tb) - 1} in {b}")
        for k, (x, y) in enumerate(zip(ta, tb)):
            if x != y:
                problems.append(f"runs.csv line {k + 1} differs:\n  {x}\n  {y}")
                break
    ma, mb = meta_without_invocation(os.path.join(a, "meta.json")), \
        meta_without_invocation(os.path.join(b, "meta.json"))
    if ma != mb:
        da, db = dict(ma), dict(mb)
        keys = [k for k in list(da) + list(db) if da.get(k) != db.get(k)]
        problems.append(f"meta.json differs in {sorted(set(keys)) or 'key order'}")
    if trajectories:
        for r in rows_a[1:]:
            name = os.path.join("trajectories", r[0] + ".csv")
            with open(os.path.join(a, name), "rb") as f:
                x = f.read()
            with open(os.path.join(b, name), "rb") as f:
                y = f.read()
            if x != y:
                problems.append(f"{name} differs")
                break
    for p in problems:
        print(f"compare-bench-outputs: {p}", file=sys.stderr)
    if not problems:
        print(f"compare-bench-outputs: {a} and {b} hold the same {len(ta) - 1} rows "
              f"(timing/host columns and invocation keys aside)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
