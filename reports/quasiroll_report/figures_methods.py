"""Method-comparison figures: work-precision (one facet per problem),
constraint drift, and the stability charts (one per stability_<axis> group).
"""

import math
import textwrap

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import NullFormatter, NullLocator

from . import selection as sel
from .data import is_finite
from .plotting import (MissingData, NOT_RUN_COLOUR, UNKNOWN_COLOUR, cause_colour,
                       legend_below_log_data, points_under_legend,
                       fmt, new_figure, no_data, positive, save_figure,
                       text_colour)
from .data import is_variant
from .problems import (coupling_line, dae_marker, method_style, nlp_colour, plot_style,
                       problem_label)

WP_METRICS = [
    ("err_pos_rms", "RMS position error vs reference [m]"),
    ("err_force_rms", "RMS contact-force error vs reference [N]"),
]


def _failed_note(ctx):
    if not ctx.failed_only:
        return ""
    return (" Omitted because all their runs failed: "
            + ", ".join(ctx.failed_only) + ".")


def style_legend_handles(rows, extra=(), styles=None):
    """Legend proxies: colour = NLP, marker = integrator, line = coupling,
    then one entry per option variant (hollow marker, its own dashes)."""
    handles = []
    for nlp in sorted({r["nlp"] for r in rows}):
        handles.append(Line2D([], [], color=nlp_colour(nlp), linewidth=3,
                              label=f"NLP {nlp}"))
    for dae in sorted({r["dae"] for r in rows}):
        handles.append(Line2D([], [], color="#444444", marker=dae_marker(dae),
                              linestyle="none", label=f"DAE {dae}"))
    for coupling in sorted({r["coupling"] for r in rows}):
        handles.append(Line2D([], [], color="#444444", linestyle=coupling_line(coupling),
                              label=f"coupling {coupling}"))
    for method in sorted({r["method"] for r in rows if is_variant(r["method"])}):
        style = (styles or {}).get(method) or method_style(method)
        handles.append(Line2D([], [], label=method, **plot_style(style)))
    return handles + list(extra)


def _legend_axes(fig, gs_cell, handles, title=None):
    """A legend in its own grid cell, its labels wrapped (at 40, 32, 26, 20
    characters; labels already broken into lines are kept) until it ends
    inside the figure: the cell's width is fixed and a long label would be
    cut off at the figure's edge."""
    ax = fig.add_subplot(gs_cell)
    ax.axis("off")
    labels = [h.get_label() for h in handles]
    for width in (None, 40, 32, 26, 20):
        if width:
            for handle, label in zip(handles, labels):
                if "\n" not in label:
                    handle.set_label(textwrap.fill(label, width))
        legend = ax.legend(handles=handles, loc="upper left", frameon=False,
                           title=title, borderaxespad=0.0)
        fig.canvas.draw()
        if legend.get_window_extent().x1 <= fig.bbox.x1:
            break
    return ax


# ---------------------------------------------------------- work-precision

def _plot_series(ax, series, styles):
    """Each line through its rungs, the bars spanning the timing IQR (q1 to
    q3 over the repeats), every point labelled with its Δt or rtol."""
    points = []
    for line, rungs in series.items():
        style = styles.get(rungs[0]["method"]) or method_style(rungs[0]["method"])
        errs = np.array([p["err"] for p in rungs])
        walls = np.array([p["wall"] for p in rungs])
        spread = np.array([[max(p["wall"] - p["wall_q1"], 0.0) for p in rungs],
                           [max(p["wall_q3"] - p["wall"], 0.0) for p in rungs]])
        ax.errorbar(errs, walls, yerr=spread if np.any(spread > 0) else None,
                    capsize=2, elinewidth=0.8, label=line, **plot_style(style))
        for p in rungs:
            if p["label"]:
                ax.annotate(p["label"], (p["err"], p["wall"]), xytext=(3, 2),
                            textcoords="offset points", fontsize=5.5,
                            color=style.colour, alpha=0.9, zorder=4)
        points += rungs
    return points


def _draw_front(ax, front):
    """The non-dominated points (selection.dominates): black rings (not
    joined: under the tie rule the set need not be monotone)."""
    if not front:
        return
    fx = [p["err"] for p in front]
    fy = [p["wall"] for p in front]
    ax.scatter(fx, fy, s=70, facecolors="none", edgecolors="black", linewidths=0.9,
               zorder=5)


def _front_methods(series, front):
    members = {id(p) for p in front}
    return sorted(line for line, rungs in series.items()
                  if any(id(p) in members for p in rungs))


def _draw_floor(ax, estimate):
    if not is_finite(estimate) or estimate <= 0:
        return False
    ax.axvline(estimate, color="#555555", linestyle=":", linewidth=1.2)
    return True


def _draw_measured_floor(ax, low, high):
    """The measured error floor: the spread of the best methods' errors at
    their tightest settings (selection.error_floor), a shaded band."""
    if not (is_finite(low) and is_finite(high) and low > 0):
        return False
    lo, hi = ax.get_xlim()
    ax.axvspan(min(lo, low / 2), low, color="#bbbbbb", alpha=0.35, zorder=0, linewidth=0)
    ax.axvspan(low, max(high, low * 1.05), color="#e8c07a", alpha=0.35, zorder=0,
               linewidth=0)
    ax.set_xlim(lo, hi)
    return True


def _work_precision_panel(ax, problem, metric, label, spread, styles):
    series = sel.work_precision_series(None, metric, rows=problem["rows"])
    points = _plot_series(ax, series, styles)
    ax.set_title(f"{problem['label']} — {metric}", fontsize=9)
    if not points:
        no_data(ax, f"no successful run with finite {metric}")
        return series, [], (math.nan, math.nan, [])
    front = sel.non_dominated(points)
    _draw_front(ax, front)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(label)
    ax.set_ylabel("wall time [s]" + (" (median, bars q1–q3)" if spread else " (min)"))
    t_end = problem["t_end"]
    if is_finite(t_end) and t_end > 0:
        sec = ax.secondary_yaxis("right", functions=(lambda w: w / t_end,
                                                     lambda s: s * t_end))
        sec.set_ylabel("wall time per simulated second [s/s]")
    floor = sel.error_floor(series)
    _draw_measured_floor(ax, floor[0], floor[1])
    if metric == "err_pos_rms":
        _draw_floor(ax, problem["ref_err_est"])
    return series, front, floor


def figure_work_precision(ctx):
    problems = sel.work_precision_problems(ctx.runs, ctx.references)
    if not problems:
        raise MissingData("no successful run for figure 'work_precision'")
    spread = sel.has_timing_spread(ctx.runs)
    n = len(problems)
    fig = new_figure(13, 0.6 + 3.9 * n)
    gs = fig.add_gridspec(n, 3, width_ratios=[1, 1, 0.42])
    details, panels = [], []
    for i, problem in enumerate(problems):
        for j, (metric, label) in enumerate(WP_METRICS):
            ax = fig.add_subplot(gs[i, j])
            series, front, floor = _work_precision_panel(ax, problem, metric, label,
                                                         spread, ctx.styles)
            if metric == "err_pos_rms":
                details.append((problem, series, front, floor))
            panels.append({"problem": problem["label"], "metric": metric,
                           "problem_key": list(problem["key"]),
                           "t_end": sorted({r["t_end"] for r in problem["rows"]
                                            if is_finite(r["t_end"])}),
                           "scenes": sorted({r["scene"] for r in problem["rows"]}),
                           "ref_hashes": sorted({r.get("ref_hash", "") for r in problem["rows"]}),
                           "lines": list(series),
                           "front": [[p["err"], p["wall"]] for p in front],
                           "front_lines": _front_methods(series, front),
                           "labels": {line: [p["label"] for p in rungs]
                                      for line, rungs in series.items()},
                           "floor": [floor[0], floor[1]], "floor_lines": floor[2],
                           "exclusive": all(p["exclusive"] for rungs in series.values()
                                            for p in rungs),
                           "ref_err_est": problem["ref_err_est"]})
    extra = [Line2D([], [], color="black", linestyle="none", marker="o", markersize=9,
                    markerfacecolor="none", label="non-dominated (beaten by\n"
                    "> IQR in time and > 1 %\nin error by no point)"),
             Patch(facecolor="#e8c07a", alpha=0.5,
                   label="measured floor: spread of\nthe best methods' tightest\nrungs"),
             Patch(facecolor="#bbbbbb", alpha=0.5, label="below every method")]
    if any(is_finite(p["ref_err_est"]) for p in problems):
        extra.append(Line2D([], [], color="#555555", linestyle=":",
                            label="reference's estimated\nerror"))
    rows = [r for p in problems for r in p["rows"]]
    _legend_axes(fig, gs[:, 2], style_legend_handles(rows, extra, ctx.styles))
    parts = []
    for problem, series, front, floor in details:
        best = min(front, key=lambda p: p["err"]) if front else None
        parts.append(
            f"{problem['label']} (groups {', '.join(problem['groups'])}): "
            f"{sum(len(s) for s in series.values())} rungs of {len(series)} lines, "
            f"most accurate err_pos_rms {fmt(best['err']) if best else 'n/a'} m in "
            f"{fmt(best['wall']) if best else 'n/a'} s, non-dominated: "
            f"{', '.join(_front_methods(series, front)) or 'none'}; measured floor "
            + (f"{fmt(floor[0])} – {fmt(floor[1])} m ({len(floor[2])} methods)"
               if is_finite(floor[0]) else "n/a") + "; reference error "
            + (f"estimate {fmt(problem['ref_err_est'])} m (dotted line)"
               if is_finite(problem["ref_err_est"]) else "not estimated"))
    exclusive = all(p["exclusive"] for p in panels)
    timing_text = (
        "The point is the median wall time over the repeats, the bars span "
        "their interquartile range (q1–q3). " + (
            "Every run was timed alone (group key exclusive: no other run "
            "shared the cores)." if exclusive else
            "Runs of groups without the exclusive key (e.g. a tolerance ladder "
            "with one repeat) were timed while other runs shared the cores: "
            "their times are upper bounds.")
        if spread else
        "Wall time is the minimum over the repeats (these results carry no "
        "timing spread: written before wall_s_median existed), so no error bars.")
    caption = (
        "Work-precision diagrams, one row per problem (scene, mode, μ, terrain, "
        "t_end: runs of different problems are never on one chart or front). "
        "Each line is one method through its Δt (or rtol) ladder, median error "
        "over repeats, every point labelled with its Δt [s] or rtol; line style: "
        "solid = zoh, dashed = coupled; a method with non-default backend "
        "options (e.g. an adaptive RK scheme) is a line of its own, hollow "
        "markers, its own dashes. Ringed points are non-dominated: no other "
        "point of the problem is faster by more than the timing spread (the "
        "larger IQR of the two) and more accurate by more than 1 %. "
        + timing_text + " The right axis is the same time per simulated second. "
        + _checkpoint_text(rows) + _step_cap_text(rows) +
        "Errors are against the problem's reference; a zoh method holds the "
        "quasi-static twist over each Δt, so its error falls only as O(Δt) "
        "(hold error) however accurate its integrator, while the coupled "
        "methods converge at their integrator's order down to the error floor. "
        "Measured floor (tan band): from the smallest error any method reaches "
        "at its tightest rung to the largest among the methods within a factor "
        "10 of it (the spread of the best methods' tightest settings); grey: "
        "below every method; dotted line: the reference's own estimated error. "
        + " ".join(p + "." for p in parts) + _failed_note(ctx))
    record = save_figure(fig, ctx.out_dir, "fig_work_precision",
                         "1. Work-precision", caption)
    record.data = {"panels": panels, "timing": "median" if spread else "min"}
    return record


def _step_cap_text(rows):
    """Where an rtol ladder is flat because the output interval, not rtol,
    limits the step: consecutive rungs whose err_pos_rms differs by < 5 %
    while the step count stays within 25 % of one step per output interval
    (t_reached / Δt x substeps)."""
    ladders = {}
    for r in rows:
        if all(isinstance(r.get(k), (int, float)) and math.isfinite(r[k])
               for k in ("tol", "steps", "dt", "t_reached", "err_pos_rms")) \
                and r["dt"] > 0:
            ladders.setdefault((r["method"], r["dt"], r["t_end"]), []).append(r)
    notes = []
    for (method, dt, _), rungs in sorted(ladders.items(), key=lambda kv: str(kv[0])):
        rungs.sort(key=lambda r: -r["tol"])
        per_interval = [r["steps"] / max(1.0, r["t_reached"] / dt *
                                         (r.get("substeps") or 1)) for r in rungs]
        last = 0  # the plateau from the loosest rung down to rungs[last]
        while (last + 1 < len(rungs) and per_interval[last + 1] <= 1.25
               and abs(rungs[last + 1]["err_pos_rms"] - rungs[last]["err_pos_rms"])
               <= 0.05 * rungs[last]["err_pos_rms"]):
            last += 1
        if last > 0:
            notes.append(f"{method} (rtol {fmt(rungs[0]['tol'])} to "
                         f"{fmt(rungs[last]['tol'])} at Δt = {fmt(dt)} s)")
    if not notes:
        return ""
    return ("Plateaus: where an rtol ladder gives one error level, the step is "
            "limited by the output interval Δt, not by rtol (the run takes about "
            "one step per output interval, runs.csv steps): "
            + "; ".join(notes[:8]) + (f" and {len(notes) - 8} more" if len(notes) > 8
                                      else "") + ". ")


def _checkpoint_text(rows):
    """How the errors were measured: at checkpoints (runs.csv column
    `checkpoints`, docs/harness.md "Errors at checkpoints") or, in results
    written before it, at each run's own output samples."""
    counts = [r.get("checkpoints") for r in rows]
    if any(isinstance(c, (int, float)) and is_finite(c) and c > 0 for c in counts):
        return ("Every error is measured at the problem's checkpoints (fixed "
                "times every ~0.3 s and the reference's end, the same for every "
                "Δt and rtol; the method's state there from its dense output, "
                "its force the one it applies there: held over the interval in "
                "zoh), so a coarse grid cannot look accurate by skipping a force "
                "spike between its samples. ")
    return ("These results predate the checkpoints: each error is measured at "
            "the run's own output samples, where a coarse grid can miss force "
            "spikes between them. ")


# ------------------------------------------------------------------ drift

STEP_DRIFT = "drift_step_max"


def _plot_drift_vs_time(ax, ctx):
    """Drift at the samples over time, one representative run per
    integrator; returns [(integrator, sample max, drift_step_max)]."""
    reps = sel.drift_representatives(ctx.runs, ctx.trajectories.has, ctx.primary)
    summary = []
    plotted = []
    for dae, run in reps.items():
        traj = ctx.trajectories.get(run)
        if traj is None:
            continue
        drift = positive(traj["drift"])
        plotted.append(drift)
        ax.plot(traj["t"], drift, markevery=0.1, **plot_style(ctx.styles[run["method"]]),
                label=f"{run['method']}, Δt={fmt(run['dt'])} s ({problem_label(run, ctx.references)})")
        summary.append((dae, np.nanmax(drift) if np.any(np.isfinite(drift)) else math.nan,
                        run.get(STEP_DRIFT, math.nan)))
    if not summary:
        no_data(ax, "no trajectory of a successful run")
        return summary
    ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("‖H‖∞ at the samples [m, rad]")
    ax.set_title("loop-closure drift, one run per integrator", fontsize=9)
    # The lines share one colour (the NLP) and fill the axes: the legend
    # gets a band of its own below them.
    legend_below_log_data(ax, np.concatenate(plotted))
    return summary


def _plot_step_drift_bars(ax, summary):
    """The same representatives: drift at the samples against drift within
    the steps before any projection (docs/model.md §8.10)."""
    rows = [(dae, sample, step) for dae, sample, step in summary if is_finite(step)]
    y = np.arange(len(rows))
    # A zero has no bar on the log axis (positive: nan), rather than a made-up floor.
    ax.barh(y - 0.2, positive([r[1] for r in rows]), height=0.4, color="#9ecae1",
            label="at the samples (returned states)")
    ax.barh(y + 0.2, positive([r[2] for r in rows]), height=0.4, color="#de2d26",
            label="within the steps, before projection")
    ax.set_yticks(y, [r[0] for r in rows], fontsize=7)
    ax.set_xscale("log")
    ax.set_xlabel("max ‖H‖∞ over the run [m, rad]")
    ax.set_title("the same runs: where the drift is measured", fontsize=9)
    ax.legend(loc="lower right", fontsize=7)


def _plot_drift_vs_dt(ax, ctx, problem, column="drift_max"):
    rows = [r for r in problem["rows"]
            if is_finite(r.get(column, math.nan)) and r[column] > 0 and is_finite(r["dt"])]
    for line in sorted({sel.line_key(r) for r in rows}):
        mine = [r for r in rows if sel.line_key(r) == line]
        dts = sorted({r["dt"] for r in mine})
        med = [float(np.median([r[column] for r in mine if r["dt"] == dt])) for dt in dts]
        ax.plot(dts, med, **plot_style(ctx.styles[mine[0]["method"]]))
    where = "at the samples" if column == "drift_max" else "within the steps"
    ax.set_title(f"{where} — {problem['label']}", fontsize=9)
    if not rows:
        no_data(ax, f"no finite {column}")
        return 0
    ax.set_xscale("log")
    ax.set_yscale("log")
    # Ticks at the run's Δt values: a log axis over less than a decade
    # otherwise labels its minor ticks on top of each other.
    dts = sorted({r["dt"] for r in rows})
    ax.set_xticks(dts, [fmt(dt) for dt in dts])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("Δt [s]")
    ax.set_ylabel("max ‖H‖∞ over the run [m, rad]")
    return len(rows)


def figure_drift(ctx):
    problems = sel.work_precision_problems(ctx.runs, ctx.references)
    # Results from before the column (drift_step_max) draw the first row only.
    steps = any(is_finite(r.get(STEP_DRIFT, math.nan)) for r in ctx.runs)
    n = 1 + len(problems)
    fig = new_figure(4.6 * n + 2.6, 4.6 * (2 if steps else 1))
    gs = fig.add_gridspec(2 if steps else 1, n + 1,
                          width_ratios=[1.25] + [1] * (n - 1) + [0.5])
    over_time = fig.add_subplot(gs[0, 0])
    summary = _plot_drift_vs_time(over_time, ctx)
    tops = [fig.add_subplot(gs[0, k + 1]) for k in range(len(problems))]
    n_rows = sum(_plot_drift_vs_dt(ax, ctx, p) for ax, p in zip(tops, problems))
    if not summary and not n_rows:
        raise MissingData("no successful run for figure 'drift'")
    if steps:
        _plot_step_drift_bars(fig.add_subplot(gs[1, 0]), summary)
        for k, (top, p) in enumerate(zip(tops, problems)):
            bottom = fig.add_subplot(gs[1, k + 1], sharex=top, sharey=top)
            _plot_drift_vs_dt(bottom, ctx, p, STEP_DRIFT)
    rows = [r for p in problems for r in p["rows"]]
    _legend_axes(fig, gs[:, n], style_legend_handles(rows or sel.successful(ctx.runs),
                                                     styles=ctx.styles))
    parts = [f"{dae} max {fmt(v)}" + (f", within its steps {fmt(step)}" if is_finite(step) else "")
             for dae, v, step in summary]
    second = (
        " Bottom row: drift_step_max, the largest ‖H‖∞ of a state a method's steps "
        "produced before any projection moved it (docs/model.md §8.10). A method that "
        "projects, or holds H = 0 as an algebraic equation, returns states at its "
        "tolerance by construction, so the top row cannot tell what it removed: in zoh "
        "the held twist's exact flow leaves the manifold by O(Δt²) per interval, which "
        "a method integrating it freely shows only here (the same value for every such "
        "method), one solving H = 0 at every step shows its solver's tolerance, and one "
        "that damps the drift (a Baumgarte gain) shows in its samples too. "
        if steps else
        " These results predate drift_step_max (the drift within the steps, before "
        "projection): only the samples' drift is shown. ")
    caption = (
        "Loop-closure constraint drift ‖H(Θ)‖∞. Top row: at the output samples, i.e. "
        "the states the runs return; left over time for one representative run per "
        "integrator (with the NLP of the paper figures where it ran, the smallest-Δt "
        "successful zoh run on the paper scene where "
        "available, its problem in the legend), then its maximum against Δt per "
        "method (median over repeats of a setting), one panel per work-precision "
        "problem; each problem's two panels share their axes; where methods differ "
        "only in their NLP their lines coincide (the drift does not depend on it) and "
        "the NLP last in the legend covers the others." + second
        + f"This run: {'; '.join(parts) or 'no trajectories'}." + _failed_note(ctx))
    covered = points_under_legend(fig, over_time)
    record = save_figure(fig, ctx.out_dir, "fig_drift", "2. Constraint drift", caption)
    record.data = {"panels": [p["label"] for p in problems], "step_drift": steps,
                   "points_under_legend": covered}
    return record


# ------------------------------------------------------- stability charts

def _cell_colour(cell):
    return cause_colour(cell["cls"], cell["detail"])


def _rgb(colour):
    return [int(colour[k:k + 2], 16) / 255 for k in (1, 3, 5)]


def _draw_category_cells(ax, panel):
    rows, values = panel["rows"], panel["values"]
    image = np.ones((len(rows), len(values), 3))
    for i, row in enumerate(rows):
        for j in range(len(values)):
            cell = panel["cells"].get((row, j))
            image[i, j] = _rgb(_cell_colour(cell) if cell else NOT_RUN_COLOUR)
    ax.imshow(image, aspect="auto", interpolation="nearest")
    for (row, j), cell in panel["cells"].items():
        ax.text(j, rows.index(row), cell["label"], ha="center", va="center", fontsize=7,
                color=text_colour(_cell_colour(cell)))
    ax.set_xticks(range(len(values)))
    many = len(values) > 8
    ax.set_xticklabels([sel.format_value(v) for v in values],
                       rotation=45 if many else 0, ha="right" if many else "center",
                       fontsize=8)
    ax.set_xticks(np.arange(-0.5, len(values)), minor=True)


def value_edges(values, log):
    """Cell edges of sorted numeric axis values: half-way between neighbours
    (in log10 where log), half a gap beyond the ends."""
    t = np.log10(values) if log else np.asarray(values, dtype=float)
    if t.size == 1:
        half = 0.15 if log else max(0.1 * abs(float(t[0])), 0.05)
        edges = np.array([t[0] - half, t[0] + half])
    else:
        mids = 0.5 * (t[1:] + t[:-1])
        edges = np.concatenate([[t[0] - (mids[0] - t[0])], mids,
                                [t[-1] + (t[-1] - mids[-1])]])
    return 10 ** edges if log else edges


def _draw_value_cells(ax, panel):
    """A numeric axis: each column a band from half-way to its neighbours,
    positioned by value (log10 where the values span a decade), a tick and a
    dot at the value itself, the cell's text at the band's centre."""
    from matplotlib.patches import Rectangle
    from matplotlib.ticker import FixedLocator, NullFormatter, NullLocator
    rows, values = panel["rows"], [float(v) for v in panel["values"]]
    log = panel["log"]
    edges = value_edges(values, log)
    if log:
        ax.set_xscale("log")
    span = (np.log10(edges[-1] / edges[0]) if log else edges[-1] - edges[0])
    fig = ax.figure
    width_pt = ax.get_position().width * fig.get_figwidth() * 72

    def width_of(j):
        w = (np.log10(edges[j + 1] / edges[j]) if log else edges[j + 1] - edges[j])
        return w / span * width_pt

    for i, row in enumerate(rows):
        for j, value in enumerate(values):
            cell = panel["cells"].get((row, j))
            colour = _cell_colour(cell) if cell else NOT_RUN_COLOUR
            ax.add_patch(Rectangle((edges[j], i - 0.5), edges[j + 1] - edges[j], 1.0,
                                   facecolor=colour, edgecolor="white", linewidth=0.8))
            if cell is None:
                continue
            text = text_colour(colour)
            ax.plot([value], [i + 0.32], marker="o", markersize=2.5, color=text,
                    linestyle="none")
            w = width_of(j)
            if w >= 7:
                # At the band's centre, not the value: two close values (σ·Δt
                # 2.5 and 3 either side of the RK4 limit) would stack their
                # texts on the limit line.
                centre = (math.sqrt(edges[j] * edges[j + 1]) if log
                          else 0.5 * (edges[j] + edges[j + 1]))
                ax.text(centre, i, cell["label"], ha="center", va="center",
                        fontsize=7 if w >= 22 else 6, rotation=0 if w >= 22 else 90,
                        color=text, clip_on=True)
    ax.set_xlim(edges[0], edges[-1])
    ax.set_ylim(len(rows) - 0.5, -0.5)
    # Tick labels by value; a label too close to the previous one is left out
    # (the value is still ticked, and in the table below the figure).
    shown, last = [], -math.inf
    for value in values:
        at = ((np.log10(value / edges[0]) if log else value - edges[0]) / span * width_pt)
        shown.append(sel.format_value(value) if at - last >= 18 else "")
        if shown[-1]:
            last = at
    ax.xaxis.set_major_locator(FixedLocator(values))
    ax.set_xticklabels(shown, rotation=90 if len(values) > 8 else 0, fontsize=8)
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())


def _draw_stability_panel(ax, panel, axis_label, axis):
    rows = panel["rows"]
    if panel.get("numeric"):
        _draw_value_cells(ax, panel)
        xs = None
    else:
        _draw_category_cells(ax, panel)
        xs = panel["values"]
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(rows, fontsize=8)
    ax.set_yticks(np.arange(-0.5, len(rows)), minor=True)
    ax.grid(which="minor", color="white", linewidth=1.5)
    ax.grid(which="major", visible=False)
    ax.tick_params(which="minor", length=0)
    ax.set_xlabel(axis_label)
    # The marker lines' labels are ticks on the top edge: inside the cells
    # they would hide the cells' fractions.
    marks = []
    if axis == "mu" and is_finite(panel["mu_min"]):
        x = panel["mu_min"] if xs is None else sel.value_position(xs, panel["mu_min"])
        lo, hi = ax.get_xlim()
        if x is not None and min(lo, hi) <= x <= max(lo, hi):
            ax.axvline(x, color="black", linestyle=":", linewidth=2)
            marks.append((x, f"μ_min(ref) = {fmt(panel['mu_min'])}"))
    for x, substeps in panel.get("limits", []):
        lo, hi = ax.get_xlim()
        if x >= hi:
            ax.set_xlim(lo, x * (1.15 if panel.get("log") else 1.05))
        ax.axvline(x, color="#222222", linestyle="--", linewidth=1.4)
        marks.append((x, "RK4 limit σ·h = 2.785" + (f" (h = Δt/{substeps})"
                                                    if substeps != 1 else "")))
    if marks:
        top = ax.secondary_xaxis("top")
        top.set_xticks([x for x, _ in marks])
        top.set_xticklabels([text for _, text in marks], fontsize=7)
        top.xaxis.set_minor_locator(NullLocator())
        top.tick_params(length=3, pad=1)
    ax.set_title(panel["label"], fontsize=9, loc="left", pad=14 if marks else 6)


def _cause_handles(charts):
    present = {}
    for chart in charts:
        for panel in chart["panels"]:
            for cell in panel["cells"].values():
                present[(cell["cls"], cell["detail"])] = _cell_colour(cell)
    order = {"success": 0, "physical": 1, "model": 2, "numerical": 3, "unknown": 4}
    handles = []
    for (cls, detail), colour in sorted(present.items(),
                                        key=lambda kv: (order[kv[0][0]], kv[0][1])):
        if cls == "success":
            label = "success"
        elif cls == "unknown":
            label = f"cause not recorded ({detail})"
        elif cls == sel.MODEL:
            label = f"model: {detail} (left the quasi-static domain)"
        else:
            label = f"{cls}: {detail}"
        handles.append(Patch(facecolor=colour, edgecolor="#777777", label=label))
    handles.append(Patch(facecolor=NOT_RUN_COLOUR, edgecolor="#777777", label="not run"))
    return handles


def _axis_caption(chart):
    """What the caption says about the value axis, the RK4 limit and the runs
    a σ axis leaves out."""
    panels = chart["panels"]
    out = ""
    if any(p.get("numeric") for p in panels):
        scale = ("log" if any(p.get("log") for p in panels) else "linear")
        out += (f" Columns sit at their values on a {scale} axis (a band reaches "
                "half-way to the next value; the dot marks the value run, the text "
                "sits at the band's centre).")
    limits = sorted({n for p in panels for _, n in p.get("limits", [])})
    if limits:
        steps = ", ".join(f"substeps = {n}: h = Δt/{n}, line at σ·Δt = "
                          f"{sel.RK4_SIGMA_H_LIMIT * n:g}" for n in limits)
        out += (" Dashed line: the stability limit of fixed-step RK4 for the "
                "Baumgarte drift equation dH/dt = −σH, σ·h = 2.785, where h is "
                "the integrator step: h = Δt/substeps, substeps being the RK4 "
                f"steps per output interval Δt (here {steps}).")
    if chart.get("left_out"):
        out += (" Left out: " + ", ".join(chart["left_out"]) + " — integrators "
                "without a Baumgarte gain (no baumgarte_sigma in their option "
                "table), for which σ is no parameter.")
    return out


def _borrowed_cause_text(cells):
    """Caption sentence for physical cells whose runs ended in a solver
    status (SOLVER_FAILURE, SINGULAR): their colour is the reference's stop,
    met at the same place; '' without any."""
    borrowed = [c for c in cells if c["cls"] == sel.PHYSICAL
                and c.get("status") in ("SOLVER_FAILURE", "SINGULAR")]
    if not borrowed:
        return ""
    return (f" {len(borrowed)} physical cell{'s' if len(borrowed) != 1 else ''} "
            "ended in a solver status (their solves gave up) where the reference "
            "stops physically: the colour names the reference's stop; how far "
            "from it each run stopped is runs.csv err_stop_t.")


def _stability_figure(ctx, chart):
    panels = chart["panels"]
    n_cols = max(len(p["values"]) for p in panels)
    longest = max(len(r) for p in panels for r in p["rows"])
    width = min(22.0, 3.2 + 0.06 * longest + 0.62 * n_cols)
    heights = [1.3 + 0.3 * len(p["rows"]) for p in panels]
    fig = new_figure(width, max(3.0, sum(heights) + 0.4))
    gs = fig.add_gridspec(len(panels), 2, width_ratios=[max(1.0, width - 3.2), 3.0],
                          height_ratios=heights)
    for k, panel in enumerate(panels):
        _draw_stability_panel(fig.add_subplot(gs[k, 0]), panel, chart["axis_label"],
                              chart["axis"])
    _legend_axes(fig, gs[:, 1], _cause_handles([chart]), title="cell colour = outcome")
    cells = [c for p in panels for c in p["cells"].values()]
    counts = {cls: sum(1 for c in cells if c["cls"] == cls)
              for cls in ("success",) + sel.CAUSE_CLASSES}
    methods = sorted({r["method"] for r in sel.in_group(ctx.runs, chart["group"])}
                     - set(chart.get("left_out", [])))
    mu_text = "; ".join(f"{p['scene']}: μ_min(ref) {fmt(p['mu_min'])}" for p in panels
                        if chart["axis"] == "mu" and is_finite(p["mu_min"]))
    caption = (
        f"Stability along {chart['axis_label'].split(' [')[0]} (group {chart['group']}): "
        "rows are the methods that ran (nlp/dae/coupling with non-default "
        "backend options, less an option the axis sweeps), columns the axis "
        "values; colour = outcome (green success; cool colours physical causes, "
        "where the reference or the analytic μ_min fails at the same place; warm "
        "colours numerical causes, where the method fails and the reference "
        "does not; olive = the model's limit: the motion before the stop "
        "exceeded the quasi-static inertia bound, so neither the stop nor the "
        "method can be judged by this model; grey = the harness did not "
        "classify the failure); text = "
        "fraction of t_end reached (worst run of the cell, k/n failed when "
        f"repeats differ). This run: {len(methods)} methods, {counts['success']} "
        f"cells succeeded, {counts['physical']} physical, {counts['numerical']} "
        f"numerical, {counts['model']} beyond the model, {counts['unknown']} "
        "unclassified."
        + (f" Dotted line: the friction the scene needs, {mu_text} (the solver's "
           "μ_min maximised over the reference trajectory)." if mu_text else "")
        + _axis_caption(chart) + _borrowed_cause_text(cells)
        + (f" {sel.REFERENCE_FAILURE_MARK} = the reference of that cell failed "
           "numerically before t_end although its retry ladder ran "
           "(reference_stop = reference_failure, docs/harness.md): the reach "
           "past the reference's stop is not verified, so the cell's fraction "
           "is no evidence of more reach than the truth."
           if any(c.get("ref_failed") for c in cells) else "")
        + (" Unclassified failures (old results without the `cause` column) "
           "show the status the run reported; a numerical blow-up can report a "
           "quasi-static status such as INFEASIBLE_FRICTION, so do not read "
           "them as physical limits." if counts["unknown"] else ""))
    name = "fig_stability_" + chart["group"][len(sel.STABILITY_PREFIX):]
    title = f"3. Stability — {chart['axis_label'].split(' [')[0]}"
    record = save_figure(fig, ctx.out_dir, name, title, caption)
    record.data = {"group": chart["group"], "axis": chart["axis"], "panels": [
        {"scene": p["scene"], "rows": p["rows"], "label": p["label"],
         "values": [sel.format_value(v) for v in p["values"]],
         "numeric": p.get("numeric", False), "log": p.get("log", False),
         "limits": [x for x, _ in p.get("limits", [])],
         "substeps": p.get("substeps", []),
         "mu_min": p["mu_min"],
         "cells": [{"row": row, "value": sel.format_value(p["values"][j]),
                    "cls": c["cls"], "detail": c["detail"], "label": c["label"],
                    "colour": _cell_colour(c), "status": c["status"]}
                   for (row, j), c in sorted(p["cells"].items())]}
        for p in panels], "left_out": chart.get("left_out", [])}
    record.notes.append(chart)
    return record


def figure_stability(ctx):
    """One figure per stability_<axis> group (a list of records)."""
    charts = sel.stability_charts(ctx.runs, ctx.references)
    if not charts:
        raise MissingData("no stability_<axis> group in these results")
    return [_stability_figure(ctx, chart) for chart in charts]


__all__ = ["figure_work_precision", "figure_drift", "figure_stability",
           "style_legend_handles", "UNKNOWN_COLOUR"]
