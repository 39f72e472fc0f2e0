"""Method-comparison figures: work-precision, constraint drift, failure map."""

import math

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch

from . import selection as sel
from .data import is_finite
from .plotting import (MissingData, NOT_RUN_COLOUR, fmt, new_figure, no_data,
                       positive, save_figure, status_colours)

WP_METRICS = [
    ("err_pos_rms", "RMS position error vs reference [m]"),
    ("err_force_rms", "RMS contact-force error vs reference [N]"),
]


def _failed_note(ctx):
    if not ctx.failed_only:
        return ""
    return (" Omitted because all their runs failed: "
            + ", ".join(ctx.failed_only) + ".")


# ---------------------------------------------------------- work-precision

def _plot_work_precision_panel(ax, ctx, metric, label):
    series = sel.work_precision_series(ctx.runs, metric)
    points = []
    for method, rungs in series.items():
        colour, marker = ctx.styles[method]
        errs = [p[2] for p in rungs]
        walls = [p[3] for p in rungs]
        ax.plot(errs, walls, color=colour, marker=marker, label=method)
        points += list(zip(errs, walls))
    if not points:
        no_data(ax, f"no successful run with finite {metric}")
        return series, []
    front = sel.pareto_front(points)
    fx, fy = zip(*front)
    ax.step(fx, fy, where="post", color="black", linestyle="--", linewidth=1.0,
            label="Pareto front", zorder=1)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(label)
    ax.set_ylabel("wall time [s]")
    ax.set_title(metric)
    return series, front


def figure_work_precision(ctx):
    fig = new_figure(11, 4.6)
    axes = fig.subplots(1, 2)
    details = []
    for ax, (metric, label) in zip(axes, WP_METRICS):
        series, front = _plot_work_precision_panel(ax, ctx, metric, label)
        details.append((metric, series, front))
    if not any(series for _, series, _ in details):
        raise MissingData("no successful run for figure 'work_precision'")
    axes[-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
    pos = details[0]
    best = min(pos[2], key=lambda p: p[0]) if pos[2] else None
    front_methods = _front_methods(pos[1], pos[2])
    caption = (
        "Work-precision diagram (SciMLBenchmarks convention): each line is one "
        "method through its Δt/tolerance ladder (median over repeats), the "
        "dashed black step is the Pareto front over all methods. "
        f"This run: {sum(len(s) for s in pos[1].values())} rungs of "
        f"{len(pos[1])} methods; most accurate err_pos_rms {fmt(best[0]) if best else 'n/a'} m "
        f"in {fmt(best[1]) if best else 'n/a'} s; on the position front: "
        f"{', '.join(front_methods) or 'none'}." + _failed_note(ctx))
    return save_figure(fig, ctx.out_dir, "fig_work_precision",
                       "1. Work-precision", caption)


def _front_methods(series, front):
    members = set(front)
    names = [m for m, rungs in series.items()
             if any((p[2], p[3]) in members for p in rungs)]
    return sorted(names)


# ------------------------------------------------------------------ drift

def _plot_drift_vs_time(ax, ctx):
    reps = sel.drift_representatives(ctx.runs, ctx.trajectories.has)
    summary = []
    for dae, run in reps.items():
        traj = ctx.trajectories.get(run)
        if traj is None:
            continue
        colour, marker = ctx.styles[run["method"]]
        drift = positive(traj["drift"])
        ax.plot(traj["t"], drift, color=colour, marker=marker, markevery=0.1,
                label=f"{dae} ({run['method']}, Δt={fmt(run['dt'])} s)")
        summary.append((dae, np.nanmax(drift) if np.any(np.isfinite(drift)) else math.nan))
    if not summary:
        no_data(ax, "no trajectory of a successful run")
        return summary
    ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("‖H‖∞ [m, rad]")
    ax.set_title("loop-closure drift, one run per integrator")
    ax.legend(loc="best")
    return summary


def _plot_drift_vs_dt(ax, ctx):
    rows = [r for r in sel.work_precision_rows(ctx.runs)
            if is_finite(r["drift_max"]) and r["drift_max"] > 0 and is_finite(r["dt"])]
    if not rows:
        rows = [r for r in sel.successful(ctx.runs)
                if is_finite(r["drift_max"]) and r["drift_max"] > 0 and is_finite(r["dt"])]
    for method in sel.method_names(rows):
        mine = sorted((r["dt"], r["drift_max"]) for r in rows if r["method"] == method)
        dts = sorted({d for d, _ in mine})
        med = [float(np.median([v for d, v in mine if d == dt])) for dt in dts]
        colour, marker = ctx.styles[method]
        ax.plot(dts, med, color=colour, marker=marker, label=method)
    if not rows:
        no_data(ax, "no finite drift_max")
        return 0
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("Δt [s]")
    ax.set_ylabel("max ‖H‖∞ over the run [m, rad]")
    ax.set_title("drift_max vs Δt per method")
    # Up to 24 methods: the legend goes beside the panel, not over the data.
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize="small")
    return len(rows)


def figure_drift(ctx):
    fig = new_figure(14, 4.6)
    ax_t, ax_dt = fig.subplots(1, 2)
    summary = _plot_drift_vs_time(ax_t, ctx)
    n_rows = _plot_drift_vs_dt(ax_dt, ctx)
    if not summary and not n_rows:
        raise MissingData("no successful run for figure 'drift'")
    parts = [f"{dae} max {fmt(v)}" for dae, v in summary]
    caption = (
        "Loop-closure constraint drift ‖H(Θ)‖∞: left over time for one "
        "representative run per integrator (smallest-Δt successful zoh run on "
        "the paper scene where available), right its maximum against Δt per "
        f"method. This run: {'; '.join(parts) or 'no trajectories'}."
        + _failed_note(ctx))
    return save_figure(fig, ctx.out_dir, "fig_drift", "2. Constraint drift",
                       caption)


# ------------------------------------------------------------ failure map

def _status_grid(smap, colours):
    order = ["(not run)"] + list(colours)
    index = {s: i for i, s in enumerate(order)}
    grid = np.zeros((len(smap["methods"]), len(smap["columns"])), dtype=int)
    for i, method in enumerate(smap["methods"]):
        for j, cell in enumerate(smap["cells"][method]):
            grid[i, j] = index[cell[0]] if cell else 0
    cmap = ListedColormap([NOT_RUN_COLOUR] + [colours[s] for s in colours])
    return grid, cmap, len(order)


def _label_cells(ax, smap):
    for i, method in enumerate(smap["methods"]):
        for j, cell in enumerate(smap["cells"][method]):
            if cell and cell[1]:
                ax.text(j, i, cell[1], ha="center", va="center", fontsize=7,
                        color="white")


def _mark_groups(ax, smap):
    columns = smap["columns"]
    starts = [j for j, c in enumerate(columns)
              if j == 0 or c["group"] != columns[j - 1]["group"]]
    for k, start in enumerate(starts):
        end = starts[k + 1] if k + 1 < len(starts) else len(columns)
        if start > 0:
            ax.axvline(start - 0.5, color="black", linewidth=1.5)
        ax.text((start + end - 1) / 2, -0.7, columns[start]["group"],
                ha="center", va="bottom", fontsize=8, fontweight="bold")
    return [columns[s]["group"] for s in starts]


def _mark_mu_min(ax, smap, groups):
    marks = []
    for group in groups:
        x, mu_min = sel.mu_min_position(smap["columns"], group)
        if x is None:
            continue
        ax.axvline(x, color="black", linestyle=":", linewidth=2)
        ax.text(x, len(smap["methods"]) - 0.5, f" μ_min={fmt(mu_min)}",
                ha="left", va="bottom", fontsize=8, rotation=0,
                bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "none"})
        marks.append((group, mu_min))
    return marks


def figure_failure_map(ctx):
    smap = sel.stability_map(ctx.runs)
    if not smap["columns"]:
        raise MissingData("no runs for figure 'failure_map'")
    colours = status_colours(smap["statuses"])
    n_rows, n_cols = len(smap["methods"]), len(smap["columns"])
    width = min(30.0, max(8.0, 4.0 + 0.42 * n_cols))
    height = max(3.2, 2.4 + 0.32 * n_rows)
    fig = new_figure(width, height)
    ax = fig.add_subplot()
    grid, cmap, n_colours = _status_grid(smap, colours)
    ax.imshow(grid, cmap=cmap, vmin=-0.5, vmax=n_colours - 0.5, aspect="auto",
              interpolation="nearest")
    ax.set_xticks(range(n_cols))
    ax.set_xticklabels([c["label"] for c in smap["columns"]], rotation=60,
                       ha="right", fontsize=7)
    ax.set_yticks(range(n_rows))
    ax.set_yticklabels(smap["methods"], fontsize=8)
    ax.set_xticks(np.arange(-0.5, n_cols), minor=True)
    ax.set_yticks(np.arange(-0.5, n_rows), minor=True)
    ax.grid(which="minor", color="white", linewidth=1.0)
    ax.grid(which="major", visible=False)
    ax.tick_params(which="minor", length=0)
    ax.set_ylim(n_rows - 0.5, -1.0)
    _label_cells(ax, smap)
    groups = _mark_groups(ax, smap)
    marks = _mark_mu_min(ax, smap, groups)
    handles = [Patch(facecolor=colours[s], label=s) for s in colours]
    handles.append(Patch(facecolor=NOT_RUN_COLOUR, edgecolor="#999999",
                         label="not run"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              title="status")
    ax.set_xlabel("condition (Δt [s], σΔt [-], μ [-], roughness)")
    ax.set_ylabel("method (nlp/dae/coupling)")
    n_fail = sum(1 for m in smap["methods"] for c in smap["cells"][m]
                 if c and c[0] != "success")
    n_cells = sum(1 for m in smap["methods"] for c in smap["cells"][m] if c)
    caption = (
        "Stability/failure map: rows are methods, columns the conditions of each "
        "stability-sweep group; a cell is coloured by the run's status "
        "(the most common failure when repeats differ, labelled k/n failed). "
        f"This run: {n_fail} of {n_cells} cells failed"
        + ("; μ_min " + ", ".join(f"{fmt(m)} ({g})" for g, m in marks)
           + " marked by the dotted line" if marks else "") + ".")
    record = save_figure(fig, ctx.out_dir, "fig_failure_map",
                         "3. Stability / failure map", caption)
    record.notes.append(smap)
    return record
