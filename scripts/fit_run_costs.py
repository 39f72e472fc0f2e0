#!/usr/bin/python3
"""Calibrates the a-priori run cost (bench/harness/cost_model.cc) from a measured suite.

    /usr/bin/python3 scripts/fit_run_costs.py DIR

DIR: the output of `quasiroll bench --jobs 1` (runs.csv and runs/). Model
(docs/cluster.md, "Cost model"):

    cost = repeats * (c0 + holds * s[nlp, dae, coupling] * f_tol)
    holds = t_end / dt * substeps
    f_tol = (1e-8 / tol) ** p   for adaptive schemes (DP5(4), BS3(2), IDA)

s (seconds per hold interval) is the median over the successful rows of each
(nlp, dae, coupling) at tol = 1e-8 of wall_s / holds; c0 is the median
per-run overhead outside the timed loop (elapsed between consecutive
runs/<id>.csv files minus repeats * wall_s: initial configuration, metrics,
files); p is the least-squares slope of log(wall_s / (holds * s)) against
log(1e-8 / tol) over the adaptive rows of other tolerances. Prints the
table of s and the model's accuracy against the elapsed times. The
backends' BackendInfo cost hints (solvers/registry.cc,
integrators/registry.cc) come from this table: an NLP's cost_ratio is its
s with the default integrator in zoh over the default NLP's, an
integrator's seconds_per_hold_{zoh,coupled} its s with the default NLP.
"""
import math
import os
import sys

import numpy as np
import pandas as pd


def main():
    d = pd.read_csv(os.path.join(sys.argv[1], "runs.csv"), keep_default_na=False,
                    na_values=["nan"])
    d["mtime"] = [os.stat(os.path.join(sys.argv[1], "runs", r + ".csv")).st_mtime_ns
                  / 1e9 for r in d.run_id]
    d = d.sort_values("mtime")
    d["elapsed"] = d.mtime.diff()  # first run: includes the references; dropped
    d["holds"] = d.t_end / d.dt * d.substeps
    d["adaptive"] = (d.dae == "ida") | (d.rk_method != "rk4")
    ok = d[(d.status == "success") & (d.wall_s > 0)]
    base = ok[(~ok.adaptive) | (ok.tol == 1e-8)]
    s = (base.wall_s / base.holds).groupby([base.nlp, base.dae, base.coupling]).median()
    c0 = (d.elapsed - d.repeats * d.wall_s).dropna().median()
    tolrows = ok[ok.adaptive & (ok.tol != 1e-8)]
    x, y = [], []
    for _, r in tolrows.iterrows():
        key = (r.nlp, r.dae, r.coupling)
        if key in s.index:
            x.append(math.log(1e-8 / r.tol))
            y.append(math.log(r.wall_s / (r.holds * s[key])))
    p = float(np.dot(x, y) / np.dot(x, x)) if x else 0.0
    print(f"c0 = {c0:.4g} s, p = {p:.3f} (from {len(x)} rows)")
    print("seconds per hold, {nlp, dae, coupling}:")
    for (nlp, dae, cpl), v in s.items():
        print(f'      {{{{"{nlp}", "{dae}", Coupling::k{cpl.capitalize()}}}, {v:.3g}}},')
    # Accuracy of the model against each run's elapsed time.
    def predict(r):
        key = (r.nlp, r.dae, r.coupling)
        sv = s[key] if key in s.index else float(s.median())
        f = (1e-8 / r.tol) ** p if r.adaptive else 1.0
        return r.repeats * (c0 + r.holds * sv * f)
    d["pred"] = d.apply(predict, axis=1)
    e = d.dropna(subset=["elapsed"])
    e = e[e.elapsed > 0]
    ratio = np.log10(e.pred / e.elapsed)
    full = e[e.status == "success"]
    rf = np.log10(full.pred / full.elapsed)
    print(f"all {len(e)} rows: |log10(pred/elapsed)| median {ratio.abs().median():.2f}, "
          f"90% {ratio.abs().quantile(0.9):.2f}; successful {len(full)}: median "
          f"{rf.abs().median():.2f}, 90% {rf.abs().quantile(0.9):.2f}")
    print(f"sum elapsed {e.elapsed.sum():.1f} s, sum predicted {e.pred.sum():.1f} s; "
          f"Spearman rank correlation {e.pred.rank().corr(e.elapsed.rank()):.3f}")


if __name__ == "__main__":
    main()
