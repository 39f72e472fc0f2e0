"""Choosing which runs go into which figure, and the numbers computed from
runs.csv alone (no plotting here, so everything is unit-testable)."""

import math
from collections import Counter, OrderedDict

import numpy as np

from .data import is_finite, is_success

PAPER_SCENE = "paper"
PAPER_MU = 0.5
WORK_PRECISION_GROUP = "work_precision"
MU_SWEEP_GROUP = "mu_sweep"

_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
            "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"]
_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p"]


# ---------------------------------------------------------------- methods

def method_names(runs):
    return sorted({run["method"] for run in runs})


def method_styles(runs):
    """{method: (colour, marker)}, stable: assigned in sorted method order."""
    styles = OrderedDict()
    for index, method in enumerate(method_names(runs)):
        colour = _COLOURS[index % len(_COLOURS)]
        marker = _MARKERS[(index // len(_COLOURS) + index) % len(_MARKERS)]
        styles[method] = (colour, marker)
    return styles


def failed_only_methods(runs):
    """Methods that have runs but no successful one, sorted."""
    ok = {run["method"] for run in runs if is_success(run)}
    return sorted({run["method"] for run in runs} - ok)


def runs_of(runs, **equal):
    return [r for r in runs if all(r.get(k) == v for k, v in equal.items())]


def successful(runs):
    return [run for run in runs if is_success(run)]


def has_group_column(runs):
    return any("suite_group" in run and run["suite_group"] for run in runs)


def in_group(runs, group):
    return [run for run in runs if run.get("suite_group", "") == group]


def mu_equals(run, mu):
    return is_finite(run["mu"]) and math.isclose(run["mu"], mu, rel_tol=1e-9,
                                                 abs_tol=1e-12)


# ------------------------------------------------------ work-precision data

def scene_with_most_runs(runs):
    counts = Counter(run["scene"] for run in runs)
    return sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[0][0]


def work_precision_rows(runs):
    """Rows of the Δt/tolerance ladders (successful ones only): every group
    whose name starts with "work_precision" (e.g. a separate, shorter ladder
    for the coupled methods)."""
    rows = ([run for run in runs
             if run.get("suite_group", "").startswith(WORK_PRECISION_GROUP)]
            if has_group_column(runs) else [])
    if not rows:
        ok = successful(runs)
        if not ok:
            return []
        rows = runs_of(ok, scene=scene_with_most_runs(ok))
    return successful(rows)


def _ladder_key(run):
    return (run["dt"] if is_finite(run["dt"]) else -1.0,
            run["tol"] if is_finite(run["tol"]) else -1.0)


def work_precision_series(runs, metric):
    """{method: [(dt, tol, error, wall_s), ...]} for the work-precision chart.

    Points are the medians over repeats (seeds) of one (dt, tol) rung,
    ordered from the coarsest rung to the finest. Only successful runs with a
    positive finite error and wall time count, so a method whose runs all
    failed never appears.
    """
    rungs = OrderedDict()
    for run in work_precision_rows(runs):
        err, wall = run[metric], run["wall_s"]
        if not (is_finite(err) and is_finite(wall) and err > 0 and wall > 0):
            continue
        rungs.setdefault(run["method"], {}).setdefault(
            _ladder_key(run), []).append((err, wall))
    series = OrderedDict()
    for method in sorted(rungs):
        points = []
        for key in sorted(rungs[method], reverse=True):
            errs, walls = zip(*rungs[method][key])
            points.append((key[0], key[1], float(np.median(errs)),
                           float(np.median(walls))))
        series[method] = points
    return series


def pareto_front(points):
    """Non-dominated (error, wall) pairs, both minimised, sorted by error."""
    front = []
    best_wall = math.inf
    for err, wall in sorted(points, key=lambda p: (p[0], p[1])):
        if wall < best_wall:
            front.append((err, wall))
            best_wall = wall
    return front


# -------------------------------------------------------------- summaries

def _median(values):
    values = [v for v in values if is_finite(v)]
    return float(np.median(values)) if values else math.nan


def _max(values):
    values = [v for v in values if is_finite(v)]
    return max(values) if values else math.nan


def method_summary(runs):
    """One dict per method: runs, status counts, medians and max drift."""
    summary = []
    for method in method_names(runs):
        mine = runs_of(runs, method=method)
        ok = successful(mine)
        summary.append({
            "method": method,
            "runs": len(mine),
            "successes": len(ok),
            "status_counts": Counter(run["status"] for run in mine),
            "median_wall_s": _median([r["wall_s"] for r in ok]),
            "median_err_pos_rms": _median([r["err_pos_rms"] for r in ok]),
            "max_drift": _max([r["drift_max"] for r in ok]),
        })
    return summary


def accuracy_bands(runs):
    """Fastest successful run per decade of err_pos_rms (work-precision rows).

    Returns [(decade_exponent, fastest_run, count_in_band)], from the most
    accurate band to the least.
    """
    bands = {}
    for run in work_precision_rows(runs):
        err, wall = run["err_pos_rms"], run["wall_s"]
        if not (is_finite(err) and err > 0 and is_finite(wall)):
            continue
        bands.setdefault(math.floor(math.log10(err)), []).append(run)
    result = []
    for decade in sorted(bands):
        members = bands[decade]
        fastest = min(members, key=lambda r: (r["wall_s"], r["method"]))
        result.append((decade, fastest, len(members)))
    return result


# ---------------------------------------------------- representative runs

def _accuracy_key(run):
    err = run["err_pos_rms"]
    dt = run["dt"] if is_finite(run["dt"]) else math.inf
    return (err if is_finite(err) else math.inf, dt, run["run_id"])


def is_reference(run):
    group = run.get("suite_group", "").lower()
    return group == "reference" or run["nlp"].lower() == "reference" \
        or run["run_id"].lower().startswith("ref")


def paper_run(runs, has_trajectory):
    """The reference, else the most accurate successful paper run at μ=0.5."""
    candidates = [r for r in successful(runs)
                  if r["scene"] == PAPER_SCENE and mu_equals(r, PAPER_MU)
                  and has_trajectory(r)]
    if not candidates:
        return None
    references = [r for r in candidates if is_reference(r)]
    if references:
        return min(references, key=_accuracy_key)
    # The figures need a fine time series over the whole scene: longest run
    # first, then the finest output interval, then the smallest error (an
    # error measured on a coarse grid is not comparable).
    longest = max((r["t_reached"] for r in candidates if is_finite(r["t_reached"])),
                  default=math.nan)
    full = [r for r in candidates if is_finite(r["t_reached"]) and r["t_reached"] >= longest]
    return min(full or candidates,
               key=lambda r: (r["dt"] if is_finite(r["dt"]) else math.inf,
                              _accuracy_key(r)))


def _preference(run, scene):
    dt = run["dt"] if is_finite(run["dt"]) else math.inf
    return (run["scene"] != scene, run["coupling"] != "zoh",
            not mu_equals(run, PAPER_MU), dt, run["run_id"])


def drift_representatives(runs, has_trajectory):
    """{dae: run}: per integrator the smallest-dt successful zoh paper run
    (falling back to other couplings and scenes) that has a trajectory."""
    chosen = OrderedDict()
    ok = [r for r in successful(runs) if has_trajectory(r)]
    for dae in sorted({r["dae"] for r in ok}):
        mine = [r for r in ok if r["dae"] == dae]
        chosen[dae] = min(mine, key=lambda r: _preference(r, PAPER_SCENE))
    return chosen


def stabilisation_pair(runs, has_trajectory, primary=None):
    """(baumgarte_run, projection_run) for Fig. 15; either may be None.

    Prefers the paper scene at μ=0.5 with the same NLP and coupling as the
    primary (paper-figure) run, then the smallest dt.
    """
    ok = [r for r in successful(runs) if has_trajectory(r)]

    def pick(dae_word):
        mine = [r for r in ok if dae_word in r["dae"].lower()]
        if not mine:
            return None

        def key(r):
            same = primary is not None and (r["nlp"], r["coupling"]) == (
                primary["nlp"], primary["coupling"])
            return (not same,) + _preference(r, PAPER_SCENE)
        return min(mine, key=key)
    return pick("baumgarte"), pick("projection")


def mu_sweep_rows(runs):
    """Rows of the μ sweep: suite_group == mu_sweep, else paper-scene rows
    when μ varies there. Failed rows included."""
    rows = in_group(runs, MU_SWEEP_GROUP) if has_group_column(runs) else []
    if rows:
        return rows
    paper = runs_of(runs, scene=PAPER_SCENE)
    mus = {r["mu"] for r in paper if is_finite(r["mu"])}
    return paper if len(mus) > 1 else []


# --------------------------------------------------------- stability map

# (name, label, value shown, value whose variation within one method makes
# it a condition). tol is left out: it is a method's own ladder knob, not a
# condition shared by all methods.
CONDITION_PARAMETERS = [
    ("dt", "Δt", lambda r: r["dt"], lambda r: r["dt"]),
    ("sigma_dt", "σΔt", lambda r: r["sigma"] * r["dt"], lambda r: r["sigma"]),
    ("mu", "μ", lambda r: r["mu"], lambda r: r["mu"]),
    ("roughness", "roughness", lambda r: r.get("roughness", math.nan),
     lambda r: r.get("roughness", math.nan)),
    ("eps", "ε", lambda r: r["eps"], lambda r: r["eps"]),
    ("scene", "scene", lambda r: r["scene"], lambda r: r["scene"]),
]


def _value_key(value):
    if isinstance(value, float):
        return (0, value if math.isfinite(value) else math.inf, "")
    return (1, 0.0, str(value))


def _same(a, b):
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) and math.isnan(b):
            return True
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15)
    return a == b


def _varies(values):
    return any(not _same(values[0], v) for v in values[1:])


def _varying_parameters(rows):
    """Condition parameters that vary within at least one method's rows."""
    varying = []
    for name, label, getter, test in CONDITION_PARAMETERS:
        if any(_varies([test(r) for r in rows if r["method"] == method])
               for method in method_names(rows)):
            varying.append((name, label, getter))
    return varying


def stability_groups(runs):
    """[(group_name, rows)] shown in the failure map."""
    if has_group_column(runs):
        groups = sorted({r["suite_group"] for r in runs
                         if "stab" in r["suite_group"].lower()})
        if MU_SWEEP_GROUP in {r["suite_group"] for r in runs}:
            groups.append(MU_SWEEP_GROUP)
        if groups:
            return [(g, in_group(runs, g)) for g in groups]
    return [(scene, runs_of(runs, scene=scene))
            for scene in sorted({r["scene"] for r in runs})]


def format_value(value):
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.3g}"
    return str(value)


def cell_status(rows):
    """(status, label) of one map cell: the most common failure if any run
    failed (label 'k/n' failed when mixed), else success."""
    failures = Counter(r["status"] for r in rows if not is_success(r))
    if not failures:
        return "success", ""
    status = sorted(failures.items(), key=lambda kv: (-kv[1], kv[0]))[0][0]
    failed = sum(failures.values())
    label = "" if failed == len(rows) else f"{failed}/{len(rows)}"
    return status, label


def stability_map(runs):
    """The failure map as data.

    Returns dict(methods, columns, cells, statuses) where columns is a list
    of dicts (group, label, values, mu, mu_min) and cells[method][i] is
    (status, label) or None when that method has no run in column i.
    """
    methods = method_names(runs)
    columns, cells = [], {m: [] for m in methods}
    for group, rows in stability_groups(runs):
        varying = _varying_parameters(rows) or [CONDITION_PARAMETERS[0][:3]]
        keys = OrderedDict()
        for r in rows:
            key = tuple(getter(r) for _, _, getter in varying)
            keys.setdefault(tuple(_value_key(v) for v in key), (key, []))[1].append(r)
        for sort_key in sorted(keys):
            values, members = keys[sort_key]
            label = ", ".join(f"{lab}={format_value(v)}"
                              for (_, lab, _), v in zip(varying, values))
            only_mu = [n for n, _, _ in varying] == ["mu"]
            mu_min = _median([r.get("mu_min", math.nan) for r in members])
            columns.append({"group": group, "label": label, "values": values,
                            "mu": values[0] if only_mu else None,
                            "mu_min": mu_min})
            for m in methods:
                mine = [r for r in members if r["method"] == m]
                cells[m].append(cell_status(mine) if mine else None)
    statuses = sorted({c[0] for m in methods for c in cells[m] if c},
                      key=lambda s: (s != "success", s))
    return {"methods": methods, "columns": columns, "cells": cells,
            "statuses": statuses}


def mu_min_position(columns, group):
    """x position (column index, fractional) of μ_min inside a μ-only group,
    or None. Interpolates linearly in μ between neighbouring columns."""
    idx = [i for i, c in enumerate(columns)
           if c["group"] == group and c["mu"] is not None]
    if len(idx) < 1:
        return None, math.nan
    mu_min = _median([columns[i]["mu_min"] for i in idx])
    if not is_finite(mu_min):
        return None, math.nan
    mus = [columns[i]["mu"] for i in idx]
    if mu_min <= mus[0]:
        return idx[0] - 0.5, mu_min
    if mu_min >= mus[-1]:
        return idx[-1] + 0.5, mu_min
    for k in range(len(mus) - 1):
        if mus[k] <= mu_min <= mus[k + 1]:
            frac = (mu_min - mus[k]) / (mus[k + 1] - mus[k])
            return idx[k] + frac, mu_min
    return None, mu_min
