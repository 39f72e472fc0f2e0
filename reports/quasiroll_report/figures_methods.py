"""Method-comparison figures: work-precision (one facet per problem),
constraint drift, and the stability charts (one per stability_<axis> group).
"""

import math

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import NullFormatter, NullLocator

from . import selection as sel
from .data import dae_option, has_dae_option, is_finite
from .plotting import (MissingData, NOT_RUN_COLOUR, UNKNOWN_COLOUR, cause_colour,
                       integrator_colour, legend_below_log_data, points_under_legend,
                       fmt, horizon_text, new_figure, no_data, positive, save_figure,
                       span_text, text_colour, wrap_label)
from .data import is_variant
from .problems import (coupling_line, dae_marker, method_style, nlp_colour, plot_style,
                       problem_label)

WP_METRICS = [
    ("err_pos_rms", "RMS position error vs reference [m]"),
    ("err_force_rms", "RMS contact-force error vs reference [N]"),
]


def _failed_note(ctx, problems):
    """The methods the figure's problems ran whose runs there all failed
    (selection.failed_only_in): not those of other groups' problems."""
    failed = sel.failed_only_in(ctx.runs, problems)
    if not failed:
        return ""
    return (" Omitted because all their runs failed: "
            + ", ".join(failed) + ".")


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
    characters, only after '/' or ',' or at a space, never inside a token:
    plotting.wrap_label; labels already broken into lines are kept) until it
    ends inside the figure: the cell's width is fixed and a long label would
    be cut off at the figure's edge."""
    ax = fig.add_subplot(gs_cell)
    ax.axis("off")
    labels = [h.get_label() for h in handles]
    for width in (None, 40, 32, 26, 20):
        if width:
            for handle, label in zip(handles, labels):
                if "\n" not in label:
                    handle.set_label(wrap_label(label, width))
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
    joined: with the tolerances the set need not be monotone)."""
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


# A measured-floor band narrower than this share of the x-axis (in log
# decades, ~4 px on a 430 px axis) is drawn as a line of fixed width too.
MIN_BAND_SHARE = 0.01
FLOOR_COLOUR = "#e8c07a"
# Where errors are not resolved (below the reference's estimated error, or
# below the force round-off floor): hatched, errors there tied for the rings.
UNRESOLVED_STYLE = {"facecolor": "none", "edgecolor": "#6a6ab0", "hatch": "////",
                    "linewidth": 0, "alpha": 0.5, "zorder": 0}


def _include_in_xlim(ax, *xs):
    """Widen the (log) x-limits so every positive finite x lies inside, by a
    margin of 0.25 decade, and fix them: a band or line added later then
    cannot move them, and a marker line left of every point is drawn."""
    lo, hi = ax.get_xlim()
    for x in xs:
        if is_finite(x) and x > 0:
            lo, hi = min(lo, x / 10 ** 0.25), max(hi, x * 10 ** 0.25)
    ax.set_xlim(lo, hi)
    return lo, hi


def _draw_measured_floor(ax, low, high):
    """The measured error floor: the spread of the best methods' errors at
    their tightest settings (selection.error_floor), a shaded band; grey
    below it. Call once the x-limits are fixed. A band narrower than
    MIN_BAND_SHARE of the axis gets a 4 pt line at its centre as well, so it
    stays visible. Returns True when the band was that narrow."""
    if not (is_finite(low) and is_finite(high) and low > 0):
        return False
    lo, hi = ax.get_xlim()
    ax.axvspan(min(lo, low / 2), low, color="#bbbbbb", alpha=0.35, zorder=0, linewidth=0)
    ax.axvspan(low, max(high, low * 1.05), color=FLOOR_COLOUR, alpha=0.35, zorder=0,
               linewidth=0)
    narrow = math.log10(max(high, low) / low) < MIN_BAND_SHARE * math.log10(hi / lo)
    if narrow:
        ax.axvline(math.sqrt(low * max(high, low)), color=FLOOR_COLOUR, alpha=0.9,
                   linewidth=4, zorder=0.5)
    ax.set_xlim(lo, hi)
    return narrow


def _draw_roundoff(ax, floor):
    if is_finite(floor) and floor > 0:
        ax.axvline(floor, color="#6a6ab0", linestyle="-.", linewidth=1.0)


def _work_precision_panel(ax, problem, metric, label, spread, styles, unresolved=math.nan):
    """One problem's chart of one metric. `unresolved`: the error below which
    points are not resolved (the reference's estimate for positions, the
    round-off floor for forces): hatched, tied at it for the rings.
    Returns (series, front, measured floor, narrow floor band)."""
    series = sel.work_precision_series(None, metric, rows=problem["rows"])
    points = _plot_series(ax, series, styles)
    ax.set_title(f"{problem['label']} — {metric}", fontsize=9)
    if not points:
        no_data(ax, f"no successful run with finite {metric}")
        return series, [], (math.nan, math.nan, []), False
    front = sel.non_dominated(points, floor=unresolved)
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
    estimate = problem["ref_err_est"] if metric == "err_pos_rms" else math.nan
    # The reference's estimate is always shown (the caption quotes it); the
    # round-off floor only near the data, not decades left of every point.
    near = any(p["err"] < 10 * unresolved for p in points) if is_finite(unresolved) else False
    lo, _ = _include_in_xlim(ax, estimate, unresolved if near else math.nan)
    floor = sel.error_floor(series)
    narrow = _draw_measured_floor(ax, floor[0], floor[1])
    if is_finite(unresolved) and unresolved > lo:
        ax.axvspan(lo, unresolved, **UNRESOLVED_STYLE)
    _draw_floor(ax, estimate)
    if metric != "err_pos_rms":
        _draw_roundoff(ax, unresolved)
    return series, front, floor, narrow


def _typical_force(ctx, problem):
    """(median |N| over the wheels and samples [N], run) of the problem's
    most accurate (err_force_rms) successful run with a trajectory: the
    force scale of its round-off floor; (nan, None) without one."""
    rows = sorted((r for r in problem["rows"] if is_finite(r.get("err_force_rms", math.nan))),
                  key=lambda r: (r["err_force_rms"], r["run_id"]))
    for run in rows:
        traj = ctx.trajectories.get(run) if ctx.trajectories.has(run) else None
        if traj is None:
            continue
        forces = np.abs(np.concatenate([traj[f"n{i}"] for i in (1, 2, 3)]))
        forces = forces[np.isfinite(forces)]
        if forces.size:
            return float(np.median(forces)), run
    return math.nan, None


def _wp_panel_data(problem, metric, series, front, floor, unresolved, narrow):
    """figures.json record of one work-precision panel."""
    return {"problem": problem["label"], "metric": metric,
            "problem_key": list(problem["key"]),
            "t_end": sorted({r["t_end"] for r in problem["rows"] if is_finite(r["t_end"])}),
            "scenes": sorted({r["scene"] for r in problem["rows"]}),
            "ref_hashes": sorted({r.get("ref_hash", "") for r in problem["rows"]}),
            "lines": list(series),
            "front": [[p["err"], p["wall"]] for p in front],
            "front_lines": _front_methods(series, front),
            "labels": {line: [p["label"] for p in rungs] for line, rungs in series.items()},
            "floor": [floor[0], floor[1]], "floor_lines": floor[2],
            "narrow_floor": narrow, "unresolved_below": unresolved,
            "exclusive": all(p["exclusive"] for rungs in series.values() for p in rungs),
            "ref_err_est": problem["ref_err_est"]}


def _wp_legend_extra(problems, roundoff, narrow):
    extra = [Line2D([], [], color="black", linestyle="none", marker="o", markersize=9,
                    markerfacecolor="none", label="non-dominated (Pareto\n"
                    "within IQR in time and\n1 % in error)"),
             Patch(facecolor=FLOOR_COLOUR, alpha=0.5,
                   label="measured floor: spread of\nthe best methods' tightest\nrungs"),
             Patch(facecolor="#bbbbbb", alpha=0.5, label="below every method")]
    if narrow:
        extra.append(Line2D([], [], color=FLOOR_COLOUR, linewidth=4,
                            label="measured floor narrower\nthan this line"))
    if any(is_finite(p["ref_err_est"]) for p in problems):
        extra.append(Line2D([], [], color="#555555", linestyle=":",
                            label="reference's estimated\nerror"))
    if roundoff:
        extra.append(Line2D([], [], color=UNRESOLVED_STYLE["edgecolor"], linestyle="-.",
                            label="force round-off floor\n1e3·ε·median |N|"))
    if roundoff or any(is_finite(p["ref_err_est"]) for p in problems):
        extra.append(Patch(facecolor="none", edgecolor=UNRESOLVED_STYLE["edgecolor"],
                           hatch="////", label="not resolved: errors\ntied at the line for\n"
                           "the rings"))
    return extra


def _force_stats(problem, series, floor):
    """The force panel's numbers for the caption: its smallest drawn error,
    how many of its points lie below the round-off `floor`, and how many
    runs have an error of exactly 0 (left off the log axis)."""
    errs = [p["err"] for rungs in series.values() for p in rungs]
    return {"min": min(errs, default=math.nan), "points": len(errs),
            "below": sum(1 for e in errs if is_finite(floor) and e < floor),
            "zero": sel.zero_error_runs(problem["rows"], "err_force_rms")}


def _unresolved_note(value, estimate):
    """' — below the reference's estimated error E m, not resolved' when
    value lies below the estimate, else ''."""
    if not (is_finite(value) and is_finite(estimate) and value < estimate):
        return ""
    return f" — below the reference's estimated error {fmt(estimate)} m, not resolved"


def _reference_error_text(problem, below):
    """The reference's own error: its estimate and the points below it; an
    analytic reference (runs.csv ref_kind analytic:*) says so."""
    estimate = problem["ref_err_est"]
    if is_finite(estimate):
        return (f"estimate {fmt(estimate)} m (dotted line; "
                + (f"{below} points below it, not resolved)" if below
                   else "no point below it)"))
    kind = str(problem.get("ref_kind", ""))
    if kind.startswith("analytic"):
        return (f"none: the reference is analytic (ref_kind {kind}), exact up to "
                "round-off, so no estimate")
    return "not estimated"


def _force_text(force, stats):
    """The force panel's part of a problem's sentence: its round-off floor,
    the points below it and the zero-error runs left off the log axis."""
    floor = sel.roundoff_floor(force[0])
    text = ""
    if force[1]:
        text += (f"; force round-off floor {fmt(floor)} N (median |N| {fmt(force[0])} N "
                 f"of {force[1]['run_id']}"
                 + ("" if stats["min"] < 10 * floor else
                    "; over a decade below every force error, off the axis") + ")")
        if stats["below"]:
            text += (f", {stats['below']} of the force panel's {stats['points']} points "
                     "below it (not resolved)")
    if stats["zero"]:
        text += (f"; {stats['zero']} run{'s' if stats['zero'] != 1 else ''} with zero "
                 "force error not drawn on the log axis")
    return text


def _wp_problem_text(problem, series, front, floor, narrow, force, force_stats):
    """A problem's sentence of the work-precision caption (position panel,
    with the force panel's round-off floor): the most accurate point and the
    measured floor say when they lie below the reference's estimated error
    (not resolved)."""
    points = [p for rungs in series.values() for p in rungs]
    best = min(points, key=lambda p: (p["err"], p["wall"])) if points else None
    estimate = problem["ref_err_est"]
    below = sum(1 for p in points if is_finite(estimate) and p["err"] < estimate)
    floor_note = ""
    if is_finite(floor[0]) and _unresolved_note(floor[0], estimate):
        floor_note = ("; its whole band" if floor[1] < estimate else "; its low end") \
            + " below the reference's estimated error, not resolved"
    return (
        f"{problem['label']} (groups {', '.join(problem['groups'])}): "
        f"{len(points)} rungs of {len(series)} lines, "
        f"most accurate err_pos_rms {fmt(best['err']) if best else 'n/a'} m in "
        f"{fmt(best['wall']) if best else 'n/a'} s"
        + (_unresolved_note(best["err"], estimate) if best else "")
        + ("" if not best or any(p is best for p in front) else
           " (not ringed: a faster point is as accurate within the tolerances)")
        + f"; non-dominated: {', '.join(_front_methods(series, front)) or 'none'}; "
        "measured floor "
        + (f"{fmt(floor[0])} – {fmt(floor[1])} m ({len(floor[2])} methods"
           + ("; narrower than 1 % of the axis: thick line" if narrow else "")
           + floor_note + ")" if is_finite(floor[0]) else "n/a")
        + "; reference error " + _reference_error_text(problem, below)
        + _force_text(force, force_stats))


# zoh lines whose observed order lies in this range fall as O(Δt).
ZOH_FIRST_ORDER = (0.8, 1.25)


def _hold_order_text(details):
    """The caption's sentence on how the errors fall with Δt, measured: per
    problem the observed orders of its zoh lines' Δt ladders
    (selection.observed_orders); O(Δt) is said only of the problems where
    every zoh line's order lies in ZOH_FIRST_ORDER, the others are named
    with their orders per integrator (median over its NLPs); a median order
    below selection.FLAT_ORDER is no order and reads 'rtol-limited (no Δt
    order)' (selection.order_text)."""
    first, other = [], []
    for problem, series, *_ in details:
        zoh = {line: rungs for line, rungs in series.items()
               if rungs and rungs[0]["coupling"] == "zoh"}
        orders = sel.observed_orders(zoh)
        if not orders:
            continue
        if all(ZOH_FIRST_ORDER[0] <= p <= ZOH_FIRST_ORDER[1] for p in orders.values()):
            first.append(f"{problem['label']} (zoh orders {min(orders.values()):.2f} "
                         f"to {max(orders.values()):.2f})")
            continue
        by_dae = {}
        for line, order in orders.items():
            point = zoh[line][0]
            by_dae.setdefault(point["dae"], []).append(
                (order, sel.is_adaptive(point.get("run", point))))
        other.append(f"{problem['label']} (zoh orders per integrator: " + ", ".join(
            f"{dae} " + sel.order_text(float(np.median([o for o, _ in ps])),
                                       all(a for _, a in ps))
            for dae, ps in sorted(by_dae.items())) + ")")
    text = ("Errors are against the problem's reference. Observed order: the "
            "least-squares slope of log error against log Δt over a line's Δt "
            "ladder (3 or more Δt at one rtol); a fit that is flat or negative "
            f"(below {sel.FLAT_ORDER:g}) is no order: for an adaptive integrator its "
            "error is set by rtol, so it reads rtol-limited (no Δt order). ")
    if first:
        text += ("A zoh method holds the quasi-static twist over each Δt; where that "
                 "hold error dominates, its error falls only as O(Δt) however accurate "
                 "its integrator: observed on " + "; ".join(first) + ". ")
    if other:
        text += ("Not so on " + "; ".join(other) + ": there the hold error does "
                 "not dominate the zoh error. ")
    if not first and not other:
        text += "No zoh line has such a ladder. "
    return text + ("A coupled method's error is set by its integrator's step or "
                   "rtol, not by a hold. ")


def _timing_text(spread, exclusive):
    if not spread:
        return ("Wall time is the minimum over the repeats (these results carry no "
                "timing spread: written before wall_s_median existed), so no error bars.")
    return ("The point is the median wall time over the repeats, the bars span "
            "their interquartile range (q1–q3). " + (
                "Every run was timed alone (group key exclusive: no other run "
                "shared the cores)." if exclusive else
                "Runs of groups without the exclusive key (e.g. a tolerance ladder "
                "with one repeat) were timed while other runs shared the cores: "
                "their times are upper bounds."))


def figure_work_precision(ctx):
    problems = sel.work_precision_problems(ctx.runs, ctx.references)
    if not problems:
        raise MissingData("no successful run for figure 'work_precision'")
    spread = sel.has_timing_spread(ctx.runs)
    n = len(problems)
    fig = new_figure(13, 0.6 + 3.9 * n)
    gs = fig.add_gridspec(n, 3, width_ratios=[1, 1, 0.42])
    details, panels, narrow_any = [], [], False
    for i, problem in enumerate(problems):
        force = _typical_force(ctx, problem)
        unresolved = {"err_pos_rms": problem["ref_err_est"],
                      "err_force_rms": sel.roundoff_floor(force[0])}
        for j, (metric, label) in enumerate(WP_METRICS):
            ax = fig.add_subplot(gs[i, j])
            series, front, floor, narrow = _work_precision_panel(
                ax, problem, metric, label, spread, ctx.styles, unresolved[metric])
            narrow_any = narrow_any or narrow
            if metric == "err_pos_rms":
                detail = (problem, series, front, floor, narrow, force)
            else:
                details.append(detail + (_force_stats(problem, series,
                                                      unresolved[metric]),))
            panels.append(_wp_panel_data(problem, metric, series, front, floor,
                                         unresolved[metric], narrow))
    # The legend names the round-off line where a force panel draws it.
    roundoff = any(d[6]["min"] < 10 * sel.roundoff_floor(d[5][0]) for d in details
                   if d[5][1])
    rows = [r for p in problems for r in p["rows"]]
    _legend_axes(fig, gs[:, 2], style_legend_handles(
        rows, _wp_legend_extra(problems, roundoff, narrow_any), ctx.styles))
    parts = [_wp_problem_text(*detail) for detail in details]
    caption = (
        "Work-precision diagrams, one row per problem (scene, mode, μ, terrain, "
        "t_end: runs of different problems are never on one chart or front). "
        "Each line is one method through its Δt (or rtol) ladder, median error "
        "over repeats, every point labelled with its Δt [s] or rtol (Δt/rtol, e.g. "
        "0.4/1e-8, on a line joining a Δt ladder and an rtol ladder where one alone "
        "would label two points alike); line style: "
        "solid = zoh, dashed = coupled; a method with non-default backend "
        "options (e.g. an adaptive RK scheme) is a line of its own, hollow "
        "markers, its own dashes. Ringed points are non-dominated (Pareto "
        "dominance with tolerances): no other point of the problem is faster by "
        "more than the timing spread (the larger IQR of the two) while at most "
        "1 % less accurate, or more accurate by more than 1 % while at most the "
        "spread slower; so of two points equally accurate within 1 % the slower "
        "one (beyond the spread) is not ringed. "
        + _timing_text(spread, all(p["exclusive"] for p in panels))
        + " The right axis is the same time per simulated second. "
        + _checkpoint_text(rows) + _step_cap_text(rows) + _hold_order_text(details) +
        "Measured floor (tan band): from the smallest error any method reaches "
        "at its tightest rung to the largest among the methods within a factor "
        "10 of it (the spread of the best methods' tightest settings; a band "
        "narrower than 1 % of its axis is drawn as a thick line); grey: "
        "below every method; dotted line: the reference's own estimated error. "
        "Hatched: errors not resolved, below the reference's estimated error "
        "(position panels) or below the force round-off floor (force panels, "
        "dash-dotted: 1e3·ε·|N|, ε = 2.2e-16 the machine epsilon, |N| the "
        "median normal force over the wheels and samples of the problem's most "
        "accurate run with a trajectory). Their order cannot be told: for the "
        "rings such errors count as equal to the floor, so among the points "
        "there only time ranks (the fastest, within the timing spread, is "
        "ringed). "
        + " ".join(p + "." for p in parts) + _failed_note(ctx, problems))
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
            notes.append((method, f" (rtol {fmt(rungs[0]['tol'])} to "
                          f"{fmt(rungs[last]['tol'])} at Δt = {fmt(dt)} s)"))
    if not notes:
        return ""
    notes = _join_nlps(notes)
    return ("Plateaus: where an rtol ladder gives one error level, the step is "
            "limited by the output interval Δt, not by rtol (the run takes about "
            "one step per output interval, runs.csv steps): "
            + "; ".join(notes[:8]) + (f" and {len(notes) - 8} more" if len(notes) > 8
                                      else "") + ". ")


def _join_nlps(notes):
    """[(method, suffix)] -> ['method suffix']: methods nlp/rest that differ
    only in their NLP and share the suffix are one note, 'rest with nlp1,
    nlp2 suffix'."""
    groups = {}
    for method, suffix in notes:
        nlp, _, rest = method.partition("/")
        key = (rest, suffix) if rest else (method, suffix)
        groups.setdefault(key, []).append(nlp if rest else None)
    out = []
    for (rest, suffix), nlps in groups.items():
        if len(nlps) > 1 and all(nlps):
            out.append(f"{rest} with {', '.join(sorted(nlps))}{suffix}")
        else:
            out += [f"{nlp}/{rest}{suffix}" if nlp else f"{rest}{suffix}" for nlp in nlps]
    return out


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


# A curve lying on an earlier one (coinciding) is drawn so, over it.
COINCIDING_STYLE = {"linestyle": (0, (4, 3)), "linewidth": 1.8}


def coinciding(a, b, rel=0.05, share=0.95):
    """True when two curves (t, y) lie on top of each other on a log axis:
    the same sample times and, at >= `share` of the samples where both are
    positive, within `rel` of each other."""
    (ta, ya), (tb, yb) = a, b
    ta, tb = np.asarray(ta, float), np.asarray(tb, float)
    ya, yb = np.asarray(ya, float), np.asarray(yb, float)
    if ta.shape != tb.shape or not np.allclose(ta, tb, rtol=0, atol=1e-12):
        return False
    both = np.isfinite(ya) & np.isfinite(yb) & (ya > 0) & (yb > 0)
    if not both.any():
        return False
    close = np.abs(ya[both] - yb[both]) <= rel * np.maximum(ya[both], yb[both])
    return float(close.mean()) >= share


def plot_integrator_curves(ax, curves, styles):
    """Curves [(run, t, y, label)] of runs with different integrators,
    coloured by integrator (plotting.integrator_colour: they may share one
    NLP and so one method colour), marker = integrator. A curve lying on an
    earlier one (coinciding) is drawn dashed over it, its markers offset.
    Returns [(dae, dae it lies on)]."""
    drawn, pairs = [], []
    for run, t, y, label in curves:
        style = plot_style(styles.get(run["method"]) or method_style(run["method"]))
        colour = integrator_colour(run["dae"])
        style.update(color=colour, markerfacecolor=(
            colour if style["markerfacecolor"] == style["color"] else style["markerfacecolor"]))
        under = next((dae for dae, tt, yy in drawn if coinciding((t, y), (tt, yy))), None)
        if under is not None:
            pairs.append((run["dae"], under))
            style.update(COINCIDING_STYLE)
        ax.plot(t, y, markevery=(0.05, 0.1) if under else 0.1, label=label, **style)
        drawn.append((run["dae"], t, y))
    return pairs


def _coincide_text(pairs):
    if not pairs:
        return ""
    return (" Coinciding curves (within 5 % at 95 % of the samples), the later "
            "drawn dashed over the first: " + "; ".join(
                f"{a} on {b}" for a, b in pairs) + ".")


def _plot_drift_vs_time(ax, ctx):
    """Drift at the samples over time, one representative run per
    integrator, colour = integrator; returns ([(integrator, sample max,
    drift_step_max)], [coinciding pairs])."""
    reps = sel.drift_representatives(ctx.runs, ctx.trajectories.has, ctx.primary)
    summary, curves = [], []
    for dae, run in reps.items():
        traj = ctx.trajectories.get(run)
        if traj is None:
            continue
        drift = positive(traj["drift"])
        curves.append((run, traj["t"], drift, f"{run['method']}, Δt={fmt(run['dt'])} s "
                       f"({problem_label(run, ctx.references)})"))
        summary.append((dae, np.nanmax(drift) if np.any(np.isfinite(drift)) else math.nan,
                        run.get(STEP_DRIFT, math.nan)))
    if not summary:
        no_data(ax, "no trajectory of a successful run")
        return summary, []
    pairs = plot_integrator_curves(ax, curves, ctx.styles)
    ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("‖H‖∞ at the samples [m, rad]")
    ax.set_title("loop-closure drift, one run per integrator", fontsize=9)
    # The lines fill the axes: the legend gets a band of its own below them.
    legend_below_log_data(ax, np.concatenate([c[2] for c in curves]))
    return summary, pairs


def _plot_step_drift_dots(ax, summary):
    """The same representatives: drift at the samples against drift within
    the steps before any projection (docs/model.md §8.10), as dots joined
    per integrator (a bar on a log axis has a length set by where the axis
    starts, not by the value)."""
    rows = [(dae, sample, step) for dae, sample, step in summary if is_finite(step)]
    y = np.arange(len(rows))
    # A zero has no dot on the log axis (positive: nan), rather than a made-up floor.
    samples, steps = positive([r[1] for r in rows]), positive([r[2] for r in rows])
    for k in range(len(rows)):
        ax.plot([samples[k], steps[k]], [y[k], y[k]], color="#bbbbbb", linewidth=1.2,
                zorder=1)
    ax.plot(samples, y, "o", color="#3182bd", markersize=6,
            label="at the samples (returned states)", zorder=2)
    ax.plot(steps, y, "D", color="#de2d26", markersize=6,
            label="within the steps, before projection", zorder=2)
    ax.set_yticks(y, [r[0] for r in rows], fontsize=7)
    ax.set_ylim(-0.6, len(rows) - 0.4)
    ax.set_xscale("log")
    ax.set_xlabel("max ‖H‖∞ over the run [m, rad]")
    ax.set_title("the same runs: where the drift is measured", fontsize=9)
    ax.legend(loc="lower right", fontsize=7)


def _plot_drift_vs_dt(ax, ctx, problem, column="drift_max"):
    """A problem's `column` against Δt, one line per method through its Δt
    ladder at one rtol (selection.drift_ladders): a point is the median over the
    repeats of one setting. Returns (rows drawn, rows left out)."""
    rows = [r for r in problem["rows"]
            if is_finite(r.get(column, math.nan)) and r[column] > 0 and is_finite(r["dt"])]
    ladders, left_out = sel.drift_ladders(rows)
    for line, (_, mine) in ladders.items():
        dts = sorted({r["dt"] for r in mine})
        med = [float(np.median([r[column] for r in mine if r["dt"] == dt])) for dt in dts]
        ax.plot(dts, med, **plot_style(ctx.styles[mine[0]["method"]]))
    where = "at the samples" if column == "drift_max" else "within the steps"
    ax.set_title(f"{where} — {problem['label']}", fontsize=9)
    if not rows:
        no_data(ax, f"no finite {column}")
        return 0, []
    ax.set_xscale("log")
    ax.set_yscale("log")
    # Ticks at the run's Δt values: a log axis over less than a decade
    # otherwise labels its minor ticks on top of each other.
    dts = sorted({r["dt"] for r in rows})
    ax.set_xticks(dts, [fmt(dt) for dt in dts])
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("Δt [s]")
    ax.set_ylabel("max ‖H‖∞ over the run [m, rad]")
    return len(rows) - len(left_out), left_out


def _left_out_rtol_text(left_out):
    """Caption sentence on the rtol-ladder rungs the drift-vs-Δt panels leave
    out (selection.drift_ladders), with the range of their drift_step_max; '' without."""
    if not left_out:
        return ""
    tols = sorted({r["tol"] for r in left_out if is_finite(r["tol"])})
    steps = [r.get(STEP_DRIFT, math.nan) for r in left_out]
    steps = [v for v in steps if is_finite(v) and v > 0]
    lines = sorted({sel.line_key(r) for r in left_out})
    return (f" Left out: {len(left_out)} runs of {len(lines)} methods' rtol ladders at "
            f"other rtols ({span_text(tols) if tols else 'n/a'}), each a setting of its "
            "own, not a repeat of the drawn point"
            + (f", their drift within the steps {span_text(steps)}" if steps else "")
            + " (Fig. 1 shows their errors against rtol).")


def figure_drift(ctx):
    problems = sel.work_precision_problems(ctx.runs, ctx.references)
    # Results from before the column (drift_step_max) draw the first row only.
    steps = any(is_finite(r.get(STEP_DRIFT, math.nan)) for r in ctx.runs)
    n = 1 + len(problems)
    fig = new_figure(4.6 * n + 2.6, 4.6 * (2 if steps else 1))
    gs = fig.add_gridspec(2 if steps else 1, n + 1,
                          width_ratios=[1.25] + [1] * (n - 1) + [0.5])
    over_time = fig.add_subplot(gs[0, 0])
    summary, pairs = _plot_drift_vs_time(over_time, ctx)
    tops = [fig.add_subplot(gs[0, k + 1]) for k in range(len(problems))]
    drawn = [_plot_drift_vs_dt(ax, ctx, p) for ax, p in zip(tops, problems)]
    n_rows = sum(n for n, _ in drawn)
    if not summary and not n_rows:
        raise MissingData("no successful run for figure 'drift'")
    if steps:
        _plot_step_drift_dots(fig.add_subplot(gs[1, 0]), summary)
        for k, (top, p) in enumerate(zip(tops, problems)):
            bottom = fig.add_subplot(gs[1, k + 1], sharex=top, sharey=top)
            drawn.append(_plot_drift_vs_dt(bottom, ctx, p, STEP_DRIFT))
    left_out = list({r["run_id"]: r for _, out in drawn for r in out}.values())
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
        "available, its problem in the legend; colour = integrator in this panel "
        "only, the NLP colour would paint them alike), then its maximum against Δt per "
        "method through its Δt ladder at one rtol (the rtol with the most Δt values, "
        "else the one the problem's Δt ladders share), a point being the median over "
        "the repeats of that one setting, one panel per work-precision "
        "problem; each problem's two panels share their axes; where methods differ "
        "only in their NLP their lines coincide (the drift does not depend on it) and "
        "the NLP last in the legend covers the others." + _left_out_rtol_text(left_out)
        + _coincide_text(pairs) + second
        + f"This run: {'; '.join(parts) or 'no trajectories'}." + _failed_note(ctx, problems))
    covered = points_under_legend(fig, over_time)
    record = save_figure(fig, ctx.out_dir, "fig_drift", "2. Constraint drift", caption)
    record.data = {"panels": [p["label"] for p in problems], "step_drift": steps,
                   "points_under_legend": covered, "coinciding": pairs}
    return record


# ---------------------------------------------------------------- Fig. 15
# (drawn here, not in figures_paper: it compares two methods' drift)

# A drift curve levels off (a plateau) when its max over the last quarter of
# the run exceeds its max before that by at most 10 %.
PLATEAU_SHARE, PLATEAU_GROWTH = 0.25, 1.1


def late_growth(t, drift, share=PLATEAU_SHARE):
    """The max of drift over the last `share` of the time span divided by
    its max before; nan when either part has no finite positive value."""
    t, drift = np.asarray(t, float), np.asarray(drift, float)
    if t.size < 2:
        return math.nan
    cut = t[0] + (1.0 - share) * (t[-1] - t[0])
    ok = np.isfinite(drift) & (drift > 0)
    late, early = drift[ok & (t >= cut)], drift[ok & (t < cut)]
    return float(late.max() / early.max()) if late.size and early.size else math.nan


def _gain(run):
    """The run's Baumgarte gain σ, or None for an integrator without one (no
    baumgarte_sigma in its option table: runs.csv sigma is then unused)."""
    if not has_dae_option(run, "baumgarte_sigma"):
        return None
    try:
        value = float(dae_option(run, "baumgarte_sigma", run["sigma"]))
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _stabilisation_text(entries):
    """What Fig. 15's runs show: per run its sample drift (max, where, final)
    and, for a Baumgarte run, whether it levels off (late_growth); then the
    within-step drifts side by side (drift_step_max), the like-with-like
    comparison: a projection run's samples are after its projection."""
    parts = []
    for run, t, drift, growth in entries:
        ok = np.isfinite(drift)
        text = (f"{run['dae']} at the samples max {fmt(float(np.max(drift[ok])))} at t = "
                f"{fmt(float(t[ok][np.argmax(drift[ok])]))} s, final "
                f"{fmt(float(drift[ok][-1]))}" if ok.any() else f"{run['dae']} no finite drift")
        if _gain(run) is not None and is_finite(growth):
            text += (f": levels off (max over the last quarter {growth:.2f}× the max "
                     "before), bounded over this run" if growth <= PLATEAU_GROWTH else
                     f": still growing at t_end (max over the last quarter {growth:.2f}× "
                     f"the max before; a plateau would be ≤ {PLATEAU_GROWTH:g}×), so this "
                     "run does not show the violation bounded")
        elif "projection" in run["dae"]:
            text += " (after its projection)"
        parts.append(text)
    out = "This run: " + "; ".join(parts) + "."
    steps = [(run["dae"], run.get(STEP_DRIFT, math.nan), run["dt"]) for run, *_ in entries]
    if all(is_finite(v) for _, v, _ in steps):
        out += (" Like with like, within the steps before any projection "
                "(drift_step_max, the marks at the right edge): "
                + ", ".join(f"{d} {fmt(v)}" for d, v, _ in steps))
        if len(steps) == 2 and min(v for _, v, _ in steps) > 0:
            (d0, v0, dt0), (d1, v1, dt1) = steps
            out += (f" ({d1} {v1 / v0:.3g}× {d0}, " + (
                f"both at Δt = {fmt(dt0)} s)" if dt0 == dt1 else
                f"{d1} at Δt = {fmt(dt1)} s, {d0} at Δt = {fmt(dt0)} s)"))
        out += "."
    else:
        out += (" These results predate drift_step_max (the drift within the steps): "
                "a projection run's curve is its drift after projection, not what its "
                "steps commit, so the curves do not compare like with like.")
    return out


# Fig. 15's drift_step_max marks: a short thick stroke over this share of
# the axis width at its right edge, a ◄ at its left end.
STEP_MARK_SHARE = 0.04


def _mark_step_drift(ax, runs):
    """Each run's drift_step_max (one maximum over the run, not a time
    series) as a short mark at the right edge of the axes, in the run's
    integrator colour, at its value on the y axis."""
    from matplotlib.transforms import blended_transform_factory
    edge = blended_transform_factory(ax.transAxes, ax.transData)
    for run in runs:
        step = run.get(STEP_DRIFT, math.nan)
        if is_finite(step) and step > 0:
            ax.plot([1.0 - STEP_MARK_SHARE, 1.0], [step, step], transform=edge,
                    color=integrator_colour(run["dae"]), linewidth=3.0,
                    solid_capstyle="butt", marker="<", markevery=[0], markersize=6,
                    zorder=4, label=f"within the steps: {run['dae']} "
                    "(drift_step_max, max over the run)")


def figure_stabilisation(ctx):
    pair = sel.stabilisation_pair(ctx.runs, ctx.trajectories.has, ctx.primary)
    pair = [r for r in pair if r is not None and ctx.trajectories.get(r) is not None]
    if not pair:
        raise MissingData("no successful rk-baumgarte or rk-projection run with "
                          "a trajectory for figure 15")
    fig = new_figure(8, 4.2)
    ax = fig.add_subplot()
    curves, entries = [], []
    for run in pair:
        traj = ctx.trajectories.get(run)
        drift = positive(traj["drift"])
        curves.append((run, traj["t"], drift, f"{run['dae']} ({run['method']}, "
                       f"Δt={fmt(run['dt'])} s" + (f", σ={fmt(_gain(run))} 1/s)"
                                                   if _gain(run) is not None else ")")))
        entries.append((run, np.asarray(traj["t"], float), drift,
                        late_growth(traj["t"], drift)))
    plot_integrator_curves(ax, curves, ctx.styles)
    _mark_step_drift(ax, pair)
    if not any(np.any(d > 0) for _, _, d, _ in curves):
        no_data(ax, "drift is zero everywhere")
    else:
        ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("‖H(Θ)‖∞ [m, rad]")
    ax.legend(loc="best", fontsize=7)
    missing = "" if len(pair) == 2 else " Only one of the pair is available."
    caption = (
        "Fig. 15 — the paper shows that Baumgarte stabilisation keeps the "
        "holonomic loop-closure violation bounded. Solid: ‖H(Θ)‖∞ at the output "
        "samples (colour = integrator); the short marks (◄) at the right edge, in "
        "the run's colour: each run's largest drift within its steps before any "
        "projection (runs.csv drift_step_max, docs/model.md §8.10), one maximum "
        "over the run, not a time series. A run levels off when its maximum over "
        "the last quarter of the "
        f"run is at most {PLATEAU_GROWTH:g}× its maximum before. "
        + _stabilisation_text(entries) + missing)
    record = save_figure(fig, ctx.out_dir, "fig15_stabilisation",
                         "Fig. 15 — constraint stabilisation", caption)
    record.data = {"legend": [t.get_text() for t in ax.get_legend().get_texts()],
                   "late_growth": {run["dae"]: g for run, _, _, g in entries},
                   "step_drift": {run["dae"]: run.get(STEP_DRIFT, math.nan)
                                  for run, *_ in entries}}
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
    at = [((np.log10(v / edges[0]) if log else v - edges[0]) / span * width_pt)
          for v in values]
    crowded = value_tick_layout(at, rotated=len(values) > 8)
    ax.xaxis.set_major_locator(FixedLocator(values))
    ax.set_xticklabels(["" if c is None else ("\n" if c else "") + sel.format_value(v)
                        for v, c in zip(values, crowded)],
                       rotation=90 if len(values) > 8 else 0, fontsize=8)
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_minor_formatter(NullFormatter())


# Value-axis tick labels: a label at least TICK_GAP_PT from the previous one
# is set as usual; a closer one (the σ·Δt axis's 3 beside 2.5, either side
# of the RK4 limit) on a second line below, where it is that far from the
# previous second-line label; only one crowded on both lines is left out.
TICK_GAP_PT = 18.0


def value_tick_layout(at, rotated=False):
    """Per tick at positions `at` [pt, increasing]: False = a label on the
    first line, True = on the second line (crowded), None = left out (the
    value is still ticked, and in the table below the figure). Rotated
    labels (many values) have no second line."""
    out, first, second = [], -math.inf, -math.inf
    for x in at:
        if x - first >= TICK_GAP_PT:
            out.append(False)
            first = x
        elif not rotated and x - second >= TICK_GAP_PT:
            out.append(True)
            second = x
        else:
            out.append(None)
    return out


def _draw_limit_line(ax, x, rows, limited_rows):
    """The RK4 limit at x, over the rows it applies to (contiguous runs of
    them), over the whole height when the panel does not say which."""
    style = {"color": "#222222", "linestyle": "--", "linewidth": 1.4}
    if limited_rows is None:
        ax.axvline(x, **style)
        return
    index = sorted(rows.index(r) for r in limited_rows if r in rows)
    start = None
    for k, i in enumerate(index):
        if start is None:
            start = i
        if k + 1 == len(index) or index[k + 1] != i + 1:
            ax.vlines(x, start - 0.5, i + 0.5, **style)
            start = None


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
            marks.append((x, f"μ_min(ref) = {fmt(panel['mu_min'])}"
                          + horizon_text(panel.get("mu_min_horizon", math.nan))))
    for x, substeps in panel.get("limits", []):
        lo, hi = ax.get_xlim()
        if x >= hi:
            ax.set_xlim(lo, x * (1.15 if panel.get("log") else 1.05))
        _draw_limit_line(ax, x, rows, panel.get("limit_rows", {}).get(substeps))
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
    # "not run" only where some (row, value) cell has no run.
    if any(len(p["cells"]) < len(p["rows"]) * len(p["values"])
           for chart in charts for p in chart["panels"]):
        handles.append(Patch(facecolor=NOT_RUN_COLOUR, edgecolor="#777777",
                             label="not run"))
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
        out += (" Dashed line (over the fixed-step RK4 rows only): the "
                "stability limit of fixed-step RK4 for the "
                "Baumgarte drift equation dH/dt = −σH, σ·h = 2.785, where h is "
                "the integrator step: h = Δt/substeps, substeps being the RK4 "
                f"steps per output interval Δt (here {steps}).")
    if chart.get("left_out"):
        out += (" Left out: " + ", ".join(chart["left_out"]) + " — integrators "
                "without a Baumgarte gain (no baumgarte_sigma in their option "
                "table), for which σ is no parameter.")
    return out


def _end_mark_text(cells):
    """Caption sentence for failed cells whose worst run reached t_end
    (selection.REACHED_END_MARKS after their 1.00); '' without any."""
    marks = sorted({c.get("end_mark", "") for c in cells} - {""})
    if not marks:
        return ""
    meaning = {"·drift": "drift_max broke the suite's drift bound",
               "·gap": "gap_max broke the suite's gap bound"}
    return (" " + "; ".join(f"1.00{m} = reached t_end, but "
                            + meaning.get(m, "failed there (see its status)")
                            for m in marks)
            + " (a failure: docs/harness.md, Verdicts).")


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


def _tol_plateau_text(ctx, chart):
    """On an rtol axis, the rows whose step the output interval caps
    (_step_cap_text, as in the work-precision caption): rtol changes
    nothing there. '' on other axes or without such rows."""
    if chart["axis"] != "tol":
        return ""
    text = _step_cap_text(sel.successful(sel.in_group(ctx.runs, chart["group"])))
    return (" " + text + "In those rows rtol changes neither the steps nor the "
            "outcome.") if text else ""


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
    # Rows as drawn: a method id per swept option value (baumgarte_sigma on
    # the σ·Δt axis) is one row, its values in the columns.
    n_rows = len({row for p in panels for row in p["rows"]})
    mu_text = "; ".join(f"{p['scene']}: μ_min(ref) {fmt(p['mu_min'])}"
                        + horizon_text(p.get("mu_min_horizon", math.nan)) for p in panels
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
        f"repeats differ)." + _end_mark_text(cells)
        + f" This run: {n_rows} method row{'s' if n_rows != 1 else ''}"
        + (f" (from {len(methods)} method ids: the ids of a swept option's values "
           "share a row)" if len(methods) > n_rows else
           f" ({len(methods)} methods, split by a run setting that varies)"
           if len(methods) < n_rows else "")
        + f", {counts['success']} "
        f"cells succeeded, {counts['physical']} physical, {counts['numerical']} "
        f"numerical, {counts['model']} beyond the model, {counts['unknown']} "
        "unclassified."
        + (f" Dotted line: the friction the scene needs, {mu_text} (the solver's "
           "μ_min maximised over the reference trajectory of the panel's t_end; "
           "over a longer horizon, as in Figs. 13–14, it can be larger)."
           if mu_text else "")
        + _tol_plateau_text(ctx, chart)
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
         "limit_rows": {str(n): names for n, names in p.get("limit_rows", {}).items()},
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
           "figure_stabilisation",
           "style_legend_handles", "UNKNOWN_COLOUR"]
