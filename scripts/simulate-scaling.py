#!/usr/bin/python3
"""Planned wall time of a suite on K ranks / N array tasks, by simulation.

    quasiroll bench --suite S --out X --plan > plan.csv
    quasiroll bench --suite S --out SAMPLE --jobs 1 --filter '0$'   # a slice
    /usr/bin/python3 scripts/simulate-scaling.py plan.csv SAMPLE [--ranks=1,8,64,256]
                                                 [--scale=F]

--scale=F multiplies every cost (e.g. the measuring run's CPU time / elapsed
time when the machine was shared, to estimate an idle machine; default 1).

Per-run cost (seconds of one core of the machine that measured SAMPLE):
  * a run of the slice: its measured elapsed time in the --jobs 1 run (time
    between consecutive runs/<id>.csv files; the first run after the
    references: from the last reference file), i.e. the run, its repeats,
    initial configuration, metrics and files;
  * any other run: its a-priori estimate (plan.csv, bench/harness/shard.h) times the
    median of measured/estimated over the slice's runs of the same group,
    NLP, integrator and coupling (else same NLP, integrator and coupling;
    else all): the model calibrated on this suite, including which runs
    stop early;
  * a reference: its measured wall_s (SAMPLE/references/<hash>.json) if the
    slice computed it, else its estimate times the median ratio of the
    measured references.

Schedules simulated (assumptions: no communication or file-system cost, no
start-up cost, every rank/task as fast as the measuring machine, runs and
references as independent tasks except that a run needs its reference):
  mpi      quasiroll-mpi with K ranks: rank 0 only dispatches (K-1 workers;
           K = 1: rank 0 runs everything); dynamic greedy list scheduling,
           references first, then ready runs, each biggest estimated cost
           first, to whichever worker is free (as bench/cluster/mpi_main.cc);
  mpi+0    the same if rank 0 computed as well (K workers), for comparison;
  array    a Slurm array of N = K tasks (bench --shard I/N, the partition of
           bench/harness/shard.cc reproduced here): each task computes the
           references of its runs, then its runs; wall = the longest task,
           every task starting at once (no queue wait);
  bound    max(total work / K, longest reference + run chain).
"""
import csv
import heapq
import math
import os
import statistics
import sys
from collections import defaultdict


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def measured_costs(sample):
    rows = read_csv(os.path.join(sample, "runs.csv"))
    refs_dir = os.path.join(sample, "references")
    ref_wall = {}
    last_ref = 0.0
    if os.path.isdir(refs_dir):
        for name in os.listdir(refs_dir):
            path = os.path.join(refs_dir, name)
            if name.endswith(".json"):
                import json
                with open(path) as f:
                    j = json.load(f)
                if j.get("wall_s") is not None:
                    ref_wall[j["hash"]] = float(j["wall_s"])
            last_ref = max(last_ref, os.stat(path).st_mtime_ns / 1e9)
    times = sorted((os.stat(os.path.join(sample, "runs", r["run_id"] + ".csv")).st_mtime_ns
                    / 1e9, r["run_id"]) for r in rows)
    run_cost = {}
    prev = last_ref
    for t, rid in times:
        run_cost[rid] = max(t - prev, 0.0)
        prev = t
    return run_cost, ref_wall


def costs(plan, sample):
    run_measured, ref_measured = measured_costs(sample)
    ratios = defaultdict(list)
    for r in plan:
        if r["run_id"] in run_measured:
            est = float(r["estimated_cost_s"])
            ratio = run_measured[r["run_id"]] / est
            ratios[("g", r["suite_group"], r["nlp"], r["dae"], r["coupling"])].append(ratio)
            ratios[("m", r["nlp"], r["dae"], r["coupling"])].append(ratio)
            ratios["all"].append(ratio)
    med = {k: statistics.median(v) for k, v in ratios.items()}
    run_cost = {}
    for r in plan:
        rid = r["run_id"]
        if rid in run_measured:
            run_cost[rid] = run_measured[rid]
            continue
        k = med.get(("g", r["suite_group"], r["nlp"], r["dae"], r["coupling"]),
                    med.get(("m", r["nlp"], r["dae"], r["coupling"]), med["all"]))
        run_cost[rid] = float(r["estimated_cost_s"]) * k
    ref_est = {r["reference"]: float(r["reference_cost_s"]) for r in plan}
    ref_ratios = [ref_measured[h] / ref_est[h] for h in ref_est if h in ref_measured]
    ref_k = statistics.median(ref_ratios) if ref_ratios else 1.0
    ref_cost = {h: ref_measured.get(h, e * ref_k) for h, e in ref_est.items()}
    info = {"runs_measured": sum(1 for r in plan if r["run_id"] in run_measured),
            "refs_measured": sum(1 for h in ref_est if h in ref_measured),
            "ratio_median": med["all"], "ref_ratio": ref_k}
    return run_cost, ref_cost, info


def simulate_dynamic(plan, run_cost, ref_cost, workers):
    """Greedy list scheduling as bench/cluster/mpi_main.cc: references first, then
    runs whose reference is done, biggest estimate first."""
    est = {r["run_id"]: float(r["estimated_cost_s"]) for r in plan}
    ref_est = {r["reference"]: float(r["reference_cost_s"]) for r in plan}
    waiting = defaultdict(list)
    for r in plan:
        waiting[r["reference"]].append(r["run_id"])
    refs = sorted(ref_est, key=lambda h: ref_est[h])  # pop() = biggest
    ready = []  # heap of (-estimate, run_id)
    free = list(range(workers))
    events = []  # (finish time, worker, kind, id)
    now = 0.0
    done = 0
    while True:
        while free and (refs or ready):
            w = free.pop()
            if refs:
                h = refs.pop()
                heapq.heappush(events, (now + ref_cost[h], w, "ref", h))
            else:
                _, rid = heapq.heappop(ready)
                heapq.heappush(events, (now + run_cost[rid], w, "run", rid))
        if not events:
            break
        now, w, kind, ident = heapq.heappop(events)
        free.append(w)
        if kind == "ref":
            for rid in waiting[ident]:
                heapq.heappush(ready, (-est[rid], rid))
        else:
            done += 1
    assert done == len(plan)
    return now


def shard_partition(plan, count):
    """bench/harness/shard.cc AssignShards: reference stretches in order of first
    appearance, cut at cost midpoints."""
    order, seen = [], {}
    for k, r in enumerate(plan):
        if r["reference"] not in seen:
            seen[r["reference"]] = len(order)
            order.append([])
        order[seen[r["reference"]]].append(k)
    costs = [float(r["estimated_cost_s"]) for r in plan]
    total = sum(costs)
    shard = [0] * len(plan)
    before = 0.0
    for stretch in order:
        for k in stretch:
            mid = before + costs[k] / 2
            shard[k] = min(max(int(math.floor(count * mid / total)), 0), count - 1)
            before += costs[k]
    return shard


def simulate_array(plan, run_cost, ref_cost, count):
    shard = shard_partition(plan, count)
    load = [0.0] * count
    refs = [set() for _ in range(count)]
    for k, r in enumerate(plan):
        load[shard[k]] += run_cost[r["run_id"]]
        refs[shard[k]].add(r["reference"])
    for s in range(count):
        load[s] += sum(ref_cost[h] for h in refs[s])
    return max(load), sum(len(x) for x in refs)


def fmt(seconds):
    if seconds >= 3600:
        return f"{seconds / 3600:.2f} h"
    if seconds >= 60:
        return f"{seconds / 60:.1f} min"
    return f"{seconds:.0f} s"


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    ranks = [1, 8, 64, 256]
    scale = 1.0
    for a in sys.argv[1:]:
        if a.startswith("--ranks="):
            ranks = [int(x) for x in a.split("=", 1)[1].split(",")]
        elif a.startswith("--scale="):
            scale = float(a.split("=", 1)[1])
    if len(args) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    plan = read_csv(args[0])
    run_cost, ref_cost, info = costs(plan, args[1])
    run_cost = {k: v * scale for k, v in run_cost.items()}
    ref_cost = {k: v * scale for k, v in ref_cost.items()}
    if scale != 1.0:
        print(f"costs scaled by {scale}")
    total_runs = sum(run_cost.values())
    total_refs = sum(ref_cost.values())
    chain = max(ref_cost[r["reference"]] + run_cost[r["run_id"]] for r in plan)
    print(f"{len(plan)} runs ({info['runs_measured']} measured), {len(ref_cost)} references "
          f"({info['refs_measured']} measured); measured/estimated median "
          f"{info['ratio_median']:.2f} (runs), {info['ref_ratio']:.2f} (references)")
    print(f"work: runs {fmt(total_runs)}, references {fmt(total_refs)}, total "
          f"{fmt(total_runs + total_refs)}; longest run {fmt(max(run_cost.values()))}, "
          f"longest reference + run {fmt(chain)}")
    print()
    print("| ranks / tasks K | mpi (rank 0 dispatches) | mpi+0 (rank 0 computes too) "
          "| array (N = K shards) | references computed (array) | bound |")
    print("|---|---|---|---|---|---|")
    for k in ranks:
        mpi = simulate_dynamic(plan, run_cost, ref_cost, max(k - 1, 1))
        mpi0 = simulate_dynamic(plan, run_cost, ref_cost, k)
        arr, nrefs = simulate_array(plan, run_cost, ref_cost, k)
        bound = max((total_runs + total_refs) / k, chain)
        print(f"| {k} | {fmt(mpi)} | {fmt(mpi0)} | {fmt(arr)} | {nrefs} | {fmt(bound)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
