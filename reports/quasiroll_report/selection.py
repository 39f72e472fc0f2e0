"""Choosing which runs go into which figure, and the numbers computed from
runs.csv alone (no plotting here, so everything is unit-testable)."""

import math
from collections import Counter, OrderedDict

import numpy as np

from .data import (dae_option, dae_option_known, is_finite, is_success, is_variant,
                   method_base, method_without)
from .problems import (fixed_label, group_by_problem, method_style, problem_key,
                       problem_label, scene_mode)

PAPER_SCENE = "paper"
PAPER_MU = 0.5
WORK_PRECISION_GROUP = "work_precision"
MU_SWEEP_GROUP = "mu_sweep"
TOLERANCE_GROUP = "tolerance"


# ---------------------------------------------------------------- methods

def method_names(runs):
    return sorted({run["method"] for run in runs})


def method_styles(runs):
    """{method: MethodStyle}: colour per NLP, marker per integrator, line
    style per coupling, the same in every report; an option variant hollow,
    with a dash pattern of its own among the variants of its pair."""
    names = method_names(runs)
    rank = {}
    for base in sorted({method_base(m) for m in names}):
        variants = [m for m in names if is_variant(m) and method_base(m) == base]
        rank.update((m, i) for i, m in enumerate(variants))
    return OrderedDict((m, method_style(m, rank.get(m))) for m in names)


def failed_only_methods(runs):
    """Methods that have runs but no successful one, sorted."""
    ok = {run["method"] for run in runs if is_success(run)}
    return sorted({run["method"] for run in runs} - ok)


def failed_only_in(runs, problems):
    """failed_only_methods over the runs of the given work-precision problems
    only (any status: the rows of the work-precision groups, or every run
    when there are none, whose problem_key is one of the problems' keys), so
    a figure's omission note names only methods of the problems it draws."""
    keys = {tuple(p["key"]) for p in problems}
    grouped = ([r for r in runs if is_work_precision_group(r.get("suite_group", ""))]
               if has_group_column(runs) else [])
    return failed_only_methods([r for r in grouped or runs if problem_key(r) in keys])


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


# ------------------------------------------------------------------ timing

def has_timing_spread(runs):
    return any(is_finite(r.get("wall_s_median", math.nan)) for r in runs)


def timing(run):
    """(point, low, high) wall time of a run: the median over its repeats with
    the min/max as the spread when the harness wrote them; otherwise wall_s
    (the minimum) with no spread (low = high = point)."""
    median = run.get("wall_s_median", math.nan)
    if is_finite(median):
        samples = run.get("timings") or []
        low = run.get("wall_s_min", math.nan)
        high = run.get("wall_s_max", math.nan)
        low = low if is_finite(low) else (min(samples) if samples else median)
        high = high if is_finite(high) else (max(samples) if samples else median)
        return median, low, high
    wall = run["wall_s"]
    return wall, wall, wall


def timing_quartiles(run):
    """(median, q1, q3) wall time of a run over its repeats: the harness's
    wall_s_q1 / wall_s_q3 where written, else the type-7 quartiles of
    wall_s_all (numpy's default, the harness's definition), else no spread
    (q1 = q3 = the point of `timing`)."""
    point = timing(run)[0]
    q1, q3 = run.get("wall_s_q1", math.nan), run.get("wall_s_q3", math.nan)
    if is_finite(q1) and is_finite(q3):
        return point, q1, q3
    samples = [t for t in (run.get("timings") or []) if is_finite(t)]
    if len(samples) >= 2:
        q1, q3 = np.percentile(samples, [25, 75])
        return point, float(q1), float(q3)
    return point, point, point


def timed_alone(run):
    """True when the harness timed the run with nothing else running
    (timing_exclusive = 1, group key `exclusive`)."""
    value = run.get("timing_exclusive", math.nan)
    return is_finite(value) and value >= 1


# ------------------------------------------------------ work-precision data

def scene_with_most_runs(runs):
    counts = Counter(run["scene"] for run in runs)
    return sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[0][0]


def is_work_precision_group(group):
    return group.startswith(WORK_PRECISION_GROUP) or group == TOLERANCE_GROUP


def work_precision_rows(runs):
    """Successful rows of the Δt / tolerance ladders: groups named
    work_precision* (e.g. a separate coupled ladder) and `tolerance` (the
    adaptive schemes' rtol ladder). Without groups: the scene with most runs.
    Rows of different problems are kept apart by the callers."""
    rows = ([run for run in runs
             if is_work_precision_group(run.get("suite_group", ""))]
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


def ladder_tol(rows, prefer=None):
    """The rtol of a line's Δt ladder (rows of one line, dicts with dt and
    tol; a non-finite tol counts as one value, -1): the rtol at which it has
    the most Δt values; among equals `prefer` (e.g. common_tol of the
    problem: the rtol the Δt ladders share), then the tightest. None
    without rows."""
    dts = {}
    for r in rows:
        dts.setdefault(_ladder_key(r)[1], set()).add(r["dt"])
    if not dts:
        return None
    return max(dts, key=lambda tol: (len(dts[tol]), prefer is not None and tol == prefer,
                                     -tol))


def common_tol(rows):
    """The rtol most rows share (-1 for a non-finite one; the tightest among
    equals), None without rows: a problem's Δt-ladder rtol."""
    counts = Counter(_ladder_key(r)[1] for r in rows)
    return max(counts, key=lambda tol: (counts[tol], -tol)) if counts else None


def drift_ladders(rows):
    """{line: (rtol, rows at it)}: each line's Δt ladder at its own rtol
    (ladder_tol, ties to the rtol the problem's Δt ladders share),
    and the left-out rows: the other rungs of an rtol ladder, which are
    settings of their own, not repeats. Returns (ladders, left_out)."""
    prefer = common_tol(rows)
    ladders, left_out = {}, []
    for line in sorted({line_key(r) for r in rows}):
        mine = [r for r in rows if line_key(r) == line]
        tol = ladder_tol(mine, prefer)
        at = [r for r in mine if _ladder_key(r)[1] == tol]
        ladders[line] = (tol, at)
        left_out += [r for r in mine if _ladder_key(r)[1] != tol]
    return ladders, left_out


def zero_error_runs(rows, metric):
    """How many successful rows have an error of exactly 0 in `metric`:
    work_precision_series leaves them out (no place on a log axis)."""
    return sum(1 for r in successful(rows)
               if is_finite(r.get(metric, math.nan)) and r[metric] == 0)


def line_key(run):
    """A work-precision line: the method (with its options, so a DP5(4)
    tolerance ladder is a line of its own)."""
    return run["method"]


def work_precision_series(runs, metric, rows=None):
    """{line: [point, ...]} for one problem's work-precision chart.

    A point is a dict (dt, tol, err, wall, wall_lo, wall_hi, t_end, n): the
    median error and median wall time over the rows of one (Δt, tol) rung,
    the timing spread over those rows' repeats; ordered coarsest rung first.
    Only successful rows with a positive finite error count, so a method
    whose runs all failed never appears. `rows` defaults to every
    work-precision row (callers pass one problem's rows).
    """
    rungs = OrderedDict()
    for run in (work_precision_rows(runs) if rows is None else successful(rows)):
        err = run[metric]
        wall, low, high = timing(run)
        if not (is_finite(err) and is_finite(wall) and err > 0 and wall > 0):
            continue
        rungs.setdefault(line_key(run), {}).setdefault(
            _ladder_key(run), []).append((err, wall, low, high, run,
                                          timing_quartiles(run)))
    series = OrderedDict()
    for line in sorted(rungs):
        points = []
        # A tolerance ladder: its rungs differ in rtol, not (only) in Δt; a
        # line joining a Δt ladder and an rtol ladder, where that one
        # parameter would label two rungs alike, labels both.
        n_tol, n_dt = (len({k[i] for k in rungs[line]}) for i in (1, 0))
        by_tol = n_tol > n_dt
        both = (n_tol if by_tol else n_dt) < len(rungs[line])
        for key in sorted(rungs[line], reverse=True):
            members = rungs[line][key]
            first = members[0][4]
            points.append({
                "dt": key[0], "tol": key[1],
                "err": float(np.median([m[0] for m in members])),
                "wall": float(np.median([m[1] for m in members])),
                "wall_lo": float(min(m[2] for m in members)),
                "wall_hi": float(max(m[3] for m in members)),
                "wall_q1": float(min(m[5][1] for m in members)),
                "wall_q3": float(max(m[5][2] for m in members)),
                "exclusive": all(timed_alone(m[4]) for m in members),
                "label": rung_label(key[0], key[1], by_tol, both),
                "t_end": first.get("t_end", math.nan),
                "t_reached": float(np.median([m[4]["t_reached"] for m in members])),
                "n": len(members), "run": first, "method": first["method"],
                "nlp": first["nlp"], "dae": first["dae"],
                "coupling": first["coupling"]})
        series[line] = points
    return series


def rung_label(dt, tol, by_tol, both=False):
    """A work-precision point's ladder parameter as a short label: its rtol
    ('1e-6') on a line whose rungs differ in rtol (a tolerance ladder), else
    its output interval Δt ('0.1'); with `both` (a line joining a Δt ladder
    and an rtol ladder, where one parameter alone would label two of its
    rungs alike) 'Δt/rtol' ('0.4/1e-8'), so no two points of the line carry
    one label."""
    tol_text = (f"{tol:.0e}".replace("e-0", "e-").replace("e+0", "e")
                if is_finite(tol) and tol > 0 else "")
    dt_text = f"{dt:g}" if is_finite(dt) and dt > 0 else ""
    if both and tol_text and dt_text:
        return f"{dt_text}/{tol_text}"
    if by_tol and tol_text:
        return tol_text
    return dt_text


# Relative error difference below which two work-precision points count as
# equally accurate (issue 21 item 7: "worse by more than 1 % in error").
ERROR_TIE = 0.01


def timing_spread(point):
    """IQR of a work-precision point's wall time (0 for one repeat)."""
    q1, q3 = point.get("wall_q1", math.nan), point.get("wall_q3", math.nan)
    return q3 - q1 if is_finite(q1) and is_finite(q3) and q3 >= q1 else 0.0


def resolved_error(point, floor=math.nan):
    """A point's error as far as it can be ranked: an error below `floor`
    (the reference's estimated error, or a round-off floor) is not resolved
    and counts as the floor itself (tied with every other such error)."""
    err = point["err"]
    return max(err, floor) if is_finite(floor) and floor > 0 else err


def dominates(b, a, error_tie=ERROR_TIE, floor=math.nan):
    """True when point b dominates point a (dicts with err, wall, wall_q1,
    wall_q3): Pareto dominance with tolerances, where "faster" means the
    difference of the median wall times exceeds the timing spread (the
    larger of the two IQRs) and "more accurate" means an error smaller by
    more than `error_tie` (1 %) relative. b dominates a when
      b is faster AND b's error is not worse than a's by more than 1 %, or
      b is more accurate AND b is not slower than a by more than the spread.
    So a point as accurate as another (within 1 %) but slower beyond the
    timing noise is dominated, and so is one as fast (within the spread)
    but less accurate beyond 1 %; two points within both tolerances of each
    other never dominate one another. With a `floor`, errors below it are
    not resolved and count as the floor itself (resolved_error): points
    both at or below it are equally accurate as far as can be told, so only
    time ranks them (the fastest, beyond the spread, dominates the rest)."""
    spread = max(timing_spread(a), timing_spread(b))
    ea, eb = resolved_error(a, floor), resolved_error(b, floor)
    faster = a["wall"] - b["wall"] > spread
    not_slower = b["wall"] - a["wall"] <= spread
    not_worse = eb <= ea * (1.0 + error_tie)
    more_accurate = ea > eb * (1.0 + error_tie)
    return (faster and not_worse) or (more_accurate and not_slower)


def non_dominated(points, error_tie=ERROR_TIE, floor=math.nan):
    """The points no other point dominates (`dominates`, errors below `floor`
    tied at it), sorted by error then wall time: the work-precision front of
    one problem."""
    front = [a for a in points
             if not any(dominates(b, a, error_tie, floor) for b in points if b is not a)]
    return sorted(front, key=lambda p: (p["err"], p["wall"]))


def error_floor(series):
    """The measured error floor of one problem's chart: each line's error at
    its tightest rung (smallest Δt, else smallest rtol, i.e. the last point
    of the series); the best methods are the lines whose tightest error is
    within a factor 10 of the smallest one; returns (low, high, lines): the
    spread of those errors and the lines, or (nan, nan, []) without data.
    A target below `high` is where the best methods disagree by up to their
    spread: below `low`, no method of these results reaches."""
    tightest = {line: rungs[-1]["err"] for line, rungs in series.items()
                if rungs and is_finite(rungs[-1]["err"]) and rungs[-1]["err"] > 0}
    if not tightest:
        return math.nan, math.nan, []
    low = min(tightest.values())
    best = sorted((line for line, e in tightest.items() if e <= 10 * low),
                  key=lambda line: tightest[line])
    return low, max(tightest[line] for line in best), best


# A force error below ROUNDOFF_FACTOR·ε·|F| (ε = 2.2e-16, the double
# precision machine epsilon; |F| a typical contact force of the problem) is
# round-off of the quasi-static solves, not a method's error: 1e3·ε ≈
# 2.2e-13 relative, ~3.6e-12 N for a 16 N wheel load. Errors below it are
# tied at it for the work-precision front (dominates, floor).
ROUNDOFF_FACTOR = 1e3


def roundoff_floor(typical_force):
    """ROUNDOFF_FACTOR · ε · |typical_force| [N], nan without a force."""
    if not is_finite(typical_force) or typical_force == 0:
        return math.nan
    return ROUNDOFF_FACTOR * float(np.finfo(float).eps) * abs(typical_force)


def observed_orders(series, min_rungs=3):
    """{line: p}: the observed order of each line's Δt ladder, the
    least-squares slope of log(err) against log(Δt) over its points at one
    rtol (the rtol with the most Δt values), for lines with at least
    `min_rungs` Δt values; other lines are left out."""
    orders = {}
    for line, points in series.items():
        by_tol = {}
        for p in points:
            if is_finite(p["dt"]) and p["dt"] > 0 and is_finite(p["err"]) and p["err"] > 0:
                by_tol.setdefault(p["tol"] if is_finite(p["tol"]) else None,
                                  []).append(p)
        ladder = max(by_tol.values(), key=len, default=[])
        if len({p["dt"] for p in ladder}) >= min_rungs:
            slope = np.polyfit(np.log([p["dt"] for p in ladder]),
                               np.log([p["err"] for p in ladder]), 1)[0]
            orders[line] = float(slope)
    return orders


# An observed order below this (a flat fit, or an error that grows as Δt
# shrinks) is no Δt order: the ladder's error is set by something else.
FLAT_ORDER = 0.5


def is_adaptive(run):
    """True for an integrator whose step follows rtol: the SUNDIALS ones
    (ida, cvode-*) and an RK scheme other than the fixed-step rk4."""
    dae = str(run.get("dae", ""))
    if dae.startswith("rk-"):
        return str(dae_option(run, "rk_method", "rk4")) != "rk4"
    return bool(dae)


def order_text(order, adaptive):
    """An observed order for a caption: '4.0'; a flat or negative one (below
    FLAT_ORDER) is no order: 'rtol-limited (no Δt order)' for an adaptive
    integrator, whose error its rtol sets, else 'flat (no Δt order)'."""
    if order < FLAT_ORDER:
        return "rtol-limited (no Δt order)" if adaptive else "flat (no Δt order)"
    return f"{order + 0.0:.1f}"


def recommendation_targets(points, floor_low):
    """Target errors E for the recommendation table: every decade 10^k from
    the largest error of the chart's points down to the first decade at or
    below the measured floor's low end."""
    errs = [p["err"] for p in points if is_finite(p["err"]) and p["err"] > 0]
    if not errs:
        return []
    top = math.ceil(math.log10(max(errs)))
    bottom = math.floor(math.log10(min(errs)))
    if is_finite(floor_low) and floor_low > 0:
        bottom = max(bottom, math.floor(math.log10(floor_low)))
    return [10.0 ** k for k in range(top, bottom - 1, -1)]


def recommendations(series, targets):
    """[dict] one per target E: the fastest point (median wall time) whose
    error is <= E, its timing spread, and the `ties`: the other methods whose
    own fastest point <= E is not slower than the winner by more than the
    larger IQR of the two (indistinguishable at this timing spread). A
    target no point reaches has winner None."""
    best_per_line = {}
    out = []
    for target in targets:
        best_per_line = {}
        for line, rungs in series.items():
            ok = [p for p in rungs if p["err"] <= target]
            if ok:
                best_per_line[line] = min(ok, key=lambda p: (p["wall"], p["err"]))
        if not best_per_line:
            out.append({"target": target, "winner": None, "line": None, "ties": []})
            continue
        line, winner = min(best_per_line.items(),
                           key=lambda kv: (kv[1]["wall"], kv[1]["err"], kv[0]))
        ties = sorted(other for other, p in best_per_line.items() if other != line
                      and p["wall"] - winner["wall"]
                      <= max(timing_spread(p), timing_spread(winner)))
        out.append({"target": target, "winner": winner, "line": line, "ties": ties,
                    "iqr": timing_spread(winner), "candidates": len(best_per_line)})
    return out


def recommendation_tables(runs, references=None, metric="err_pos_rms"):
    """Per work-precision problem: (problem, floor, [recommendation]) for
    decade targets of `metric` (recommendation_targets, recommendations)."""
    out = []
    for problem in work_precision_problems(runs, references):
        series = work_precision_series(None, metric, rows=problem["rows"])
        points = [p for rungs in series.values() for p in rungs]
        floor = error_floor(series)
        out.append((problem, floor,
                    recommendations(series, recommendation_targets(points, floor[0]))))
    return out


def pareto_front(points):
    """Non-dominated (error, wall) pairs, both minimised, sorted by error."""
    front = []
    best_wall = math.inf
    for err, wall in sorted(points, key=lambda p: (p[0], p[1])):
        if wall < best_wall:
            front.append((err, wall))
            best_wall = wall
    return front


def work_precision_problems(runs, references=None):
    """[dict] one per problem of the work-precision rows: key, label, rows,
    t_end, ref_err_est (max over the rows, nan if absent), groups."""
    problems = []
    for key, rows in group_by_problem(work_precision_rows(runs)):
        estimates = [r["ref_err_est"] for r in rows if is_finite(r.get("ref_err_est"))]
        problems.append({
            "key": key, "label": problem_label(rows[0], references),
            "rows": rows, "t_end": rows[0].get("t_end", math.nan),
            "ref_hash": rows[0].get("ref_hash", ""),
            "ref_err_est": max(estimates) if estimates else math.nan,
            # e.g. "analytic:circle" or "numerical" (runs.csv ref_kind)
            "ref_kind": rows[0].get("ref_kind", "") or "",
            "groups": sorted({r.get("suite_group", "") for r in rows})})
    return problems


# -------------------------------------------------------------- summaries

def _median(values):
    values = [v for v in values if is_finite(v)]
    return float(np.median(values)) if values else math.nan


def _max(values):
    values = [v for v in values if is_finite(v)]
    return max(values) if values else math.nan


PHYSICAL, NUMERICAL, UNKNOWN = "physical", "numerical", "unknown"
# The model's own limit (docs/harness.md, Failure causes): the motion left
# the quasi-static domain before the stop (cause_detail quasi_static_invalid).
MODEL = "model"
CAUSE_CLASSES = (PHYSICAL, NUMERICAL, MODEL, UNKNOWN)


# Statuses of runs that reached t_end but broke the suite's drift / gap bound.
BOUND_STATUSES = {"drift_exceeded": "drift_blowup", "gap_exceeded": "gap_blowup"}


def has_causes(runs):
    """True when the harness classified failures (`cause` column filled)."""
    return any(r.get("cause") for r in runs if not is_success(r))


def failure_cause(run):
    """(class, detail) of a run: ("success", "") for a success; ("physical" |
    "numerical" | "model", cause_detail) when the harness classified it; else
    ("unknown", status): an unclassified status is never presented as
    physical (INFEASIBLE_FRICTION from a blow-up looks like a friction limit)."""
    if is_success(run):
        return "success", ""
    cause = run.get("cause", "")
    if cause in (PHYSICAL, NUMERICAL, MODEL):
        return cause, run.get("cause_detail", "") or "unspecified"
    if run["status"] in BOUND_STATUSES:
        # Reached t_end past the suite's drift/gap bound: the method's error
        # by definition (docs/harness.md, Verdicts), whatever the harness wrote.
        return NUMERICAL, BOUND_STATUSES[run["status"]]
    return UNKNOWN, run["status"]


def status_text(run):
    """A run's status as the summary shows it: the status with its cause
    class, e.g. 'INFEASIBLE_FRICTION (numerical: baumgarte_instability)', so
    a blow-up that ends in a quasi-static status never reads as a physical
    limit; 'INFEASIBLE_FRICTION (unclassified)' without a cause."""
    cls, detail = failure_cause(run)
    if cls == "success":
        return run["status"]
    if cls == UNKNOWN:
        return f"{run['status']} (unclassified)"
    return f"{run['status']} ({cls}: {detail})"


def method_summary(runs):
    """One dict per method: runs, status counts, failure classes, max drift
    (at the samples and within the steps) and max KKT residual over its
    successful runs. No medians of time or
    error here: those pool different problems (see the per-problem tables)."""
    summary = []
    for method in method_names(runs):
        mine = runs_of(runs, method=method)
        ok = successful(mine)
        classes = Counter(failure_cause(r)[0] for r in mine if not is_success(r))
        summary.append({
            "method": method,
            "runs": len(mine),
            "successes": len(ok),
            "status_counts": Counter(run["status"] for run in mine),
            # The status with its cause class (status_text): what the table shows.
            "status_causes": Counter(status_text(run) for run in mine),
            "cause_counts": classes,
            "max_drift": _max([r["drift_max"] for r in ok]),
            # Before any projection (docs/model.md §8.10); nan for older results.
            "max_step_drift": _max([r.get("drift_step_max", math.nan) for r in ok]),
            "max_kkt": _max([r.get("kkt_residual", math.nan) for r in ok]),
        })
    return summary


def accuracy_bands(runs, references=None):
    """Fastest successful run per decade of err_pos_rms, per problem.

    Returns [(problem, [(decade_exponent, fastest_run, count_in_band)])],
    bands from the most accurate to the least; speed = median wall time over
    repeats where recorded (else wall_s, the minimum)."""
    result = []
    for problem in work_precision_problems(runs, references):
        bands = {}
        for run in problem["rows"]:
            err, wall = run["err_pos_rms"], timing(run)[0]
            if not (is_finite(err) and err > 0 and is_finite(wall)):
                continue
            bands.setdefault(math.floor(math.log10(err)), []).append(run)
        rows = []
        for decade in sorted(bands):
            members = bands[decade]
            fastest = min(members, key=lambda r: (timing(r)[0], r["method"]))
            rows.append((decade, fastest, len(members)))
        result.append((problem, rows))
    return result


def fastest_within(rows, target):
    """The fastest successful row with err_pos_rms <= target, or None."""
    ok = [r for r in rows if is_finite(r["err_pos_rms"]) and r["err_pos_rms"] <= target
          and is_finite(timing(r)[0])]
    return min(ok, key=lambda r: (timing(r)[0], r["method"])) if ok else None


# ---------------------------------------------------- representative runs

def _accuracy_key(run):
    err = run["err_pos_rms"]
    dt = run["dt"] if is_finite(run["dt"]) else math.inf
    return (err if is_finite(err) else math.inf, dt, run["run_id"])


def is_reference(run):
    group = run.get("suite_group", "").lower()
    return group == "reference" or run["nlp"].lower() == "reference" \
        or run["run_id"].lower().startswith("ref")


def pvc_scene(runs, references):
    """The pvc-mode twin of the paper scene (e.g. `paper_pvc`), or None."""
    names = sorted({r["scene"] for r in runs if r["scene"] != PAPER_SCENE
                    and scene_mode(r, references) == "pvc"})
    twins = [n for n in names if n.startswith(PAPER_SCENE)]
    return (twins or names or [None])[0]


def paper_run(runs, has_trajectory, scene=PAPER_SCENE):
    """The reference, else the most accurate successful run of `scene` at μ=0.5."""
    candidates = [r for r in successful(runs)
                  if r["scene"] == scene and mu_equals(r, PAPER_MU)
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


def snapshot_pair(runs, has_trajectory, pvc, primary=None):
    """(paper run, pvc run) for Fig. 5 and the replay: two successful μ = 0.5
    runs with a trajectory of one method (nlp/dae/coupling with its
    options) that differ in as little else as the results allow: equal
    t_end first, then equal Δt, then the fewest other differing settings
    (ε, seed, roughness, rtol, NLP tolerance); among equals the longest
    pair, the primary run, the settings and method nearest the primary's,
    a pair from one suite group, then each scene's own order (paper_run:
    reference, longest, finest Δt, most accurate). Without a common method
    the two scenes' own picks (paper_run). pvc = the pvc scene name or None."""
    primary = primary if primary is not None else paper_run(runs, has_trajectory)
    if pvc is None or primary is None:
        return primary, None if pvc is None else paper_run(runs, has_trajectory, pvc)

    def ok(scene):
        return [r for r in successful(runs) if r["scene"] == scene
                and mu_equals(r, PAPER_MU) and has_trajectory(r)]
    pairs = [(p, q) for p in ok(primary["scene"]) for q in ok(pvc)
             if p["method"] == q["method"]]
    if not pairs:
        return primary, paper_run(runs, has_trajectory, pvc)

    def differs(p, q, name):
        return not same_value(p.get(name, math.nan), q.get(name, math.nan))
    settings = ("eps", "seed", "roughness", "tol", "nlp_tol")

    def own_order(r):
        reached = r["t_reached"] if is_finite(r["t_reached"]) else -math.inf
        dt = r["dt"] if is_finite(r["dt"]) else math.inf
        return (not is_reference(r), -reached, dt, _accuracy_key(r))

    def key(pair):
        p, q = pair
        return (differs(p, q, "t_end"), differs(p, q, "dt"),
                sum(differs(p, q, n) for n in settings),
                max(own_order(p)[1], own_order(q)[1]), p["run_id"] != primary["run_id"],
                sum(differs(p, primary, n) for n in settings),
                sum(p[n] != primary[n] for n in ("method", "nlp", "dae", "coupling")),
                p.get("suite_group") != q.get("suite_group"), own_order(p), own_order(q))
    return min(pairs, key=key)


def _preference(run, scene):
    dt = run["dt"] if is_finite(run["dt"]) else math.inf
    return (is_variant(run["method"]), run["scene"] != scene, run["coupling"] != "zoh",
            not mu_equals(run, PAPER_MU), dt, run["run_id"])


def drift_representatives(runs, has_trajectory, primary=None):
    """{dae: run}: per integrator the smallest-dt successful zoh paper run
    (falling back to other couplings and scenes) that has a trajectory,
    preferring the primary (paper-figure) run's NLP so that every panel
    shows the integrators with the solver of the other figures."""
    chosen = OrderedDict()
    ok = [r for r in successful(runs) if has_trajectory(r)]

    def key(r):
        same = primary is not None and r["nlp"] == primary["nlp"]
        return (not same,) + _preference(r, PAPER_SCENE)
    for dae in sorted({r["dae"] for r in ok}):
        chosen[dae] = min((r for r in ok if r["dae"] == dae), key=key)
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
    """Rows of the μ sweep: suite_group == mu_sweep; without a group column,
    paper-scene rows when μ varies there. Failed rows included."""
    if has_group_column(runs):
        return in_group(runs, MU_SWEEP_GROUP)
    paper = [r for r in runs if r["scene"].startswith(PAPER_SCENE)]
    mus = {r["mu"] for r in paper if is_finite(r["mu"])}
    return paper if len(mus) > 1 else []


# --------------------------------------------------------- stability map

STABILITY_PREFIX = "stability_"

# Axis name (suffix of a stability_<axis> group, matched by prefix) -> label
# and the value of a run on that axis.
AXES = [
    ("sigma_dt", "σ·Δt [-]", lambda r: r["sigma"] * r["dt"]),
    ("sigma", "σ·Δt [-]", lambda r: r["sigma"] * r["dt"]),
    ("dt", "Δt [s]", lambda r: r["dt"]),
    ("tol", "rtol [-]", lambda r: r["tol"]),
    ("mu", "μ [-]", lambda r: r["mu"]),
    ("rough", "roughness (bump amplitude factor) [-]",
     lambda r: r.get("roughness", math.nan)),
    ("seed", "terrain seed", lambda r: r.get("seed", "")),
]
# Run settings that, when they vary within a stability group besides its
# axis, split a method into several rows (backend options, e.g. rk_method or
# baumgarte_sigma, are in the method already).
_ROW_PARAMETERS = [("dt", "Δt", lambda r: r["dt"]), ("tol", "rtol", lambda r: r["tol"]),
                   ("eps", "ε", lambda r: r["eps"])]
_AXIS_OWNS = {"sigma_dt": {"dt"}, "sigma": {"dt"}, "dt": {"dt"}, "tol": {"tol"}}
# Backend options an axis sweeps: its columns, so not part of a row's method.
_AXIS_OPTIONS = {"sigma_dt": {"baumgarte_sigma"}, "sigma": {"baumgarte_sigma"}}
# The run fields an axis sweeps, left out of its panels' titles
# (problems.fixed_label).
_AXIS_SWEEPS = {"mu": ("mu",), "rough": ("roughness",), "seed": ("seed",),
                "dt": ("dt",), "tol": ()}
# Axes whose values are numbers: positioned by value (log where they span a
# decade or more), not by column index.
NUMERIC_AXES = ("sigma_dt", "sigma", "dt", "tol", "mu", "rough")
# An axis that needs an integrator option: runs whose integrator lacks it
# (no Baumgarte gain: sigma is not a parameter of theirs) are left out.
_AXIS_NEEDS = {"sigma_dt": "baumgarte_sigma", "sigma": "baumgarte_sigma"}
# Stability limit of classical RK4 on the real axis: |1 + z + z²/2 + z³/6 +
# z⁴/24| <= 1 for z = -σh up to σh = 2.785 (the Baumgarte drift ODE
# dH/dt = -σH integrated with the fixed step h).
RK4_SIGMA_H_LIMIT = 2.785


def _value_key(value):
    if isinstance(value, float):
        return (0, value if math.isfinite(value) else math.inf, "")
    try:
        return (0, float(value), "")
    except (TypeError, ValueError):
        return (1, 0.0, str(value))


def same_value(a, b):
    """Equal run-setting values: floats within 1e-9 relative (two NaN are
    equal), anything else by ==."""
    if isinstance(a, float) and isinstance(b, float):
        if math.isnan(a) and math.isnan(b):
            return True
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-15)
    return a == b


def _varies(values):
    return any(not same_value(values[0], v) for v in values[1:])


def format_value(value):
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.3g}"
    return str(value)


def axis_of(group):
    """(axis, label, getter) of a stability_<axis> group, or None."""
    if not group.startswith(STABILITY_PREFIX):
        return None
    suffix = group[len(STABILITY_PREFIX):].lower()
    for name, label, getter in AXES:
        if suffix.startswith(name):
            return name, label, getter
    return None


def t_fraction(run):
    frac = run.get("t_reached_frac", math.nan)
    if is_finite(frac):
        return frac
    t_end = run.get("t_end", math.nan)
    if is_finite(t_end) and t_end > 0 and is_finite(run["t_reached"]):
        return run["t_reached"] / t_end
    return math.nan


def stability_cell(rows):
    """One chart cell: dict(cls, detail, frac, label, n, failed). The worst
    row decides (a failure over a success; among failures numerical, then
    unknown, then the model's limit, then physical; then the smallest
    t_reached fraction)."""
    rank = {NUMERICAL: 0, UNKNOWN: 1, MODEL: 2, PHYSICAL: 3, "success": 4}
    scored = sorted(rows, key=lambda r: (rank[failure_cause(r)[0]],
                                         t_fraction(r) if is_finite(t_fraction(r)) else 2.0,
                                         r["run_id"]))
    worst = scored[0]
    cls, detail = failure_cause(worst)
    failed = sum(1 for r in rows if not is_success(r))
    frac = t_fraction(worst)
    if cls == "success" and (not is_finite(frac) or frac >= 1.0 - 1e-12):
        label = "1"
    elif is_finite(frac):
        # rounded down: a run that stopped at 99.8 % never reads "1.00"
        label = f"{math.floor(frac * 100) / 100:.2f}".lstrip("0")
    else:
        label = "?"
    # A failure that reached t_end (e.g. drift_max beyond the suite's bound
    # at the end): "1.00" alone would read as a full run; a mark says why.
    end_mark = ""
    if cls != "success" and is_finite(frac) and frac >= 1.0 - 1e-12:
        end_mark = REACHED_END_MARKS.get(worst["status"], REACHED_END_OTHER)
        label += end_mark
    if 0 < failed < len(rows):
        label += f" ({failed}/{len(rows)})"
    # The reference itself failed numerically (runs.csv reference_stop): what
    # the runs reach past its stop is not checked against the truth.
    ref_failed = any(is_reference_failure(r) for r in rows)
    if ref_failed:
        label += REFERENCE_FAILURE_MARK
    return {"cls": cls, "detail": detail, "frac": frac, "label": label,
            "n": len(rows), "failed": failed, "status": worst["status"],
            "run_id": worst["run_id"], "ref_failed": ref_failed, "end_mark": end_mark}


# Appended to a stability cell's label whose reference failed numerically.
REFERENCE_FAILURE_MARK = "†"
# Appended to the "1.00" of a failed cell whose worst run reached t_end: why
# it failed there (the suite's drift / gap bound, docs/harness.md Verdicts).
REACHED_END_MARKS = {"drift_exceeded": "·drift", "gap_exceeded": "·gap"}
REACHED_END_OTHER = "·fail"


def is_reference_failure(run):
    """True when the run's reference stopped on its own numerical failure
    after the retry ladder (runs.csv reference_stop = reference_failure;
    docs/harness.md, Reference retries)."""
    return run.get("reference_stop", "") == "reference_failure"


def substeps_of(run):
    """Integrator steps per output interval Δt (runs.csv `substeps`; 1 when
    not recorded)."""
    value = run.get("substeps", math.nan)
    return int(value) if is_finite(value) and value >= 1 else 1


def _is_rk4(run):
    return str(dae_option(run, "rk_method", "")) == "rk4"


def rk4_limit_lines(rows):
    """[(σ·Δt, substeps)] where σ·h = RK4_SIGMA_H_LIMIT for the fixed-step
    RK4 runs among rows (h = Δt / substeps), one per substeps value."""
    steps = sorted({substeps_of(r) for r in rows if _is_rk4(r)})
    return [(RK4_SIGMA_H_LIMIT * n, n) for n in steps]


def rk4_limit_rows(rows, row_of):
    """{substeps: sorted row names} of the rows holding a fixed-step RK4 run
    with that many substeps: the rows a limit line applies to (an IDA row's
    stability has nothing to do with it)."""
    out = {}
    for r in rows:
        if _is_rk4(r):
            out.setdefault(substeps_of(r), set()).add(row_of(r))
    return {n: sorted(names) for n, names in out.items()}


def _has_axis_option(rows, option):
    """Predicate: does a row's integrator have the option a chart's axis
    sweeps? From `dae_options` / the method id (data.dae_option_known); for
    older rows that cannot tell, an integrator whose σ column varies within
    the group sweeps it, one whose σ stays put does not."""
    sweeping = {dae for dae in {r["dae"] for r in rows}
                if _varies([r["sigma"] for r in rows if r["dae"] == dae])}

    def has(run):
        known = dae_option_known(run, option)
        return known if known is not None else run["dae"] in sweeping
    return has


def _spans_decades(values, decades):
    nums = [v for v in values if isinstance(v, float) and math.isfinite(v) and v > 0]
    return len(nums) == len(values) and len(nums) > 1 and \
        math.log10(max(nums) / min(nums)) >= decades


def axis_is_numeric(axis, values):
    return axis in NUMERIC_AXES and bool(values) and all(
        isinstance(v, float) and math.isfinite(v) for v in values)


def _row_label(run, extra, options=()):
    parts = [method_without(run["method"], options)] + [
        f"{lab}={format_value(get(run))}" for _, lab, get in extra]
    return " ".join(parts)


def stability_charts(runs, references=None):
    """[chart] one per stability_<axis> group (docs: reports/README.md).

    chart = dict(group, axis, axis_label, panels); one panel per scene of the
    group: dict(scene, label, values, rows, cells, mu_min) where rows are the
    methods that ran there (split by other varying method parameters),
    values the axis values that ran, cells[(row, i)] a stability_cell or
    absent; mu_min the largest ref_mu_min of a successful reference of that
    scene (μ axis only, nan when not recorded), mu_min_horizon the t_end it
    is maximised over (mu_min_horizon).
    """
    charts = []
    groups = sorted({r.get("suite_group", "") for r in runs})
    for group in groups:
        axis = axis_of(group)
        if axis is None:
            continue
        name, label, getter = axis
        rows = in_group(runs, group)
        needs = _AXIS_NEEDS.get(name)
        if needs:
            has = _has_axis_option(rows, needs)
            left_out = sorted({r["method"] for r in rows if not has(r)})
            rows = [r for r in rows if has(r)]
        else:
            left_out = []
        owned = _AXIS_OWNS.get(name, set())
        options = _AXIS_OPTIONS.get(name, set())
        panels = []
        for scene in sorted({r["scene"] for r in rows}):
            mine = [r for r in rows if r["scene"] == scene]
            row_methods = {method_without(r["method"], options) for r in mine}
            extra = [p for p in _ROW_PARAMETERS if p[0] not in owned and any(
                _varies([p[2](r) for r in mine
                         if method_without(r["method"], options) == m])
                for m in sorted(row_methods))]
            values = sorted({_value_key(getter(r)): getter(r) for r in mine}.items())
            values = [v for _, v in values]
            row_names = sorted({_row_label(r, extra, options) for r in mine})
            cells = {}
            for row_name in row_names:
                for i, value in enumerate(values):
                    members = [r for r in mine if _row_label(r, extra, options) == row_name
                               and same_value(getter(r), value)]
                    if members:
                        cells[(row_name, i)] = stability_cell(members)
            mu_min = scene_mu_min(mine) if name == "mu" else math.nan
            numeric = axis_is_numeric(name, values)
            panels.append({"scene": scene,
                           # The parameters held fixed over the panel's runs;
                           # the swept ones (the axis) never from one row.
                           "label": fixed_label(mine, references,
                                                omit=_AXIS_SWEEPS.get(name, ())),
                           "values": values, "rows": row_names, "cells": cells,
                           "mu_min": mu_min, "numeric": numeric,
                           "mu_min_horizon": mu_min_horizon(mine, mu_min),
                           "log": numeric and _spans_decades(values, 1.0),
                           "limits": rk4_limit_lines(mine) if name in _AXIS_NEEDS else [],
                           "limit_rows": rk4_limit_rows(
                               mine, lambda r: _row_label(r, extra, options)),
                           "substeps": sorted({substeps_of(r) for r in mine})})
        charts.append({"group": group, "axis": name, "axis_label": label,
                       "panels": panels, "left_out": left_out})
    return charts


def scene_mu_min(rows):
    """The friction a scene needs: the largest `ref_mu_min` (the solver's
    μ_min maximised over a reference trajectory) among rows whose reference
    reached its end; nan when the column is absent."""
    values = [r["ref_mu_min"] for r in rows if is_finite(r.get("ref_mu_min", math.nan))
              and r.get("ref_status", "success") in ("success", "")]
    if not values:
        values = [r["ref_mu_min"] for r in rows if is_finite(r.get("ref_mu_min", math.nan))]
    return max(values) if values else math.nan


def mu_min_horizon(rows, value):
    """The horizon a scene's μ_min(ref) `value` is maximised over: the
    largest t_end of the rows whose ref_mu_min is that value [s]; nan when
    unknown."""
    ends = [r.get("t_end", math.nan) for r in rows
            if is_finite(value) and r.get("ref_mu_min") == value]
    ends = [e for e in ends if is_finite(e)]
    return max(ends) if ends else math.nan


def value_position(values, x):
    """Fractional column index of x among sorted numeric values (linear
    interpolation), or None."""
    nums = [float(v) for v in values]
    if not nums or not is_finite(x):
        return None
    if x <= nums[0]:
        return -0.5 if x < nums[0] else 0.0
    if x >= nums[-1]:
        return len(nums) - 0.5 if x > nums[-1] else len(nums) - 1.0
    for k in range(len(nums) - 1):
        if nums[k] <= x <= nums[k + 1]:
            return k + (x - nums[k]) / (nums[k + 1] - nums[k])
    return None
