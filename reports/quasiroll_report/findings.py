"""Key findings at the top of the page, generated from the data (plain text
sentences with numbers), and the per-problem tables that back them."""

import math

import numpy as np

from . import selection as sel
from .data import (dae_option, is_finite, is_success, method_options, method_without,
                   parse_method)
from .plotting import fmt, span_text
from .problems import problem_label

ERROR_TARGETS = [1e-4, 1e-6, 1e-8, 1e-10]

# Quasi-static validity: inertial load / contact load (qs_inertia_ratio). The
# neglected inertial wrench perturbs the contact forces, and so mu_min, by
# about this fraction; 1 % is an order of magnitude below the friction
# margins the study resolves (docs/model.md, "Quasi-static validity"). A
# results directory may override it (meta.json "qs_inertia_threshold").
QS_THRESHOLD_DEFAULT = 0.01


def qs_threshold(meta):
    value = meta.get("qs_inertia_threshold") if isinstance(meta, dict) else None
    try:
        value = float(value)
    except (TypeError, ValueError):
        return QS_THRESHOLD_DEFAULT, "report default"
    return (value, "meta.json") if math.isfinite(value) and value > 0 else (
        QS_THRESHOLD_DEFAULT, "report default")


def _speed_text(run):
    wall = sel.timing(run)[0]
    per = wall / run["t_reached"] if is_finite(run["t_reached"]) and run["t_reached"] > 0 \
        else math.nan
    kind = "median" if is_finite(run.get("wall_s_median", math.nan)) else "min"
    ladder = f"Δt={fmt(run['dt'])} s"
    if "rk_method" in method_options(run["method"]):  # an adaptive scheme's rung
        ladder += f", rtol={fmt(run['tol'])}"
    # The full method id: an option variant is named as such, never as its pair.
    return f"{run['method']} ({ladder}): {fmt(wall)} s {kind} wall, {fmt(per)} s per simulated s"


def work_precision_findings(runs, references):
    out = []
    for problem in sel.work_precision_problems(runs, references):
        floor = problem["ref_err_est"]
        reached = []
        for target in ERROR_TARGETS:
            if is_finite(floor) and target < floor:
                out.append(f"On {problem['label']} a position error of {fmt(target)} m is "
                           f"below the reference's estimated error ({fmt(floor)} m): "
                           "not resolvable with this reference.")
                break
            best = sel.fastest_within(problem["rows"], target)
            if best is None:
                break
            reached.append((target, best))
        for target, best in reached:
            out.append(f"For RMS position error ≤ {fmt(target)} m on {problem['label']}, "
                       f"the fastest method is {_speed_text(best)} "
                       f"(err {fmt(best['err_pos_rms'])} m).")
        if not reached:
            errs = [r["err_pos_rms"] for r in problem["rows"] if is_finite(r["err_pos_rms"])]
            if errs:
                out.append(f"On {problem['label']} no run reaches {fmt(ERROR_TARGETS[0])} m; "
                           f"the most accurate has {fmt(min(errs))} m.")
    return out


def mu_findings(records):
    slip = next((r for r in records if r.name == "fig14_total_slip_vs_mu" and r.data), None)
    if slip is None:
        return []
    out = []
    per_scene = slip.data.get("per_scene", {})
    regimes = slip.data.get("regimes", {})
    if per_scene:
        from .figures_paper import slip_regime_text
        text = f"At μ={fmt(slip.data['compare_mu'])}: " + "; ".join(
            slip_regime_text(s, v, regimes.get(s)) for s, v in per_scene.items())
        sliding = {s: reg[0] for s, reg in regimes.items() if reg[0] > 0}
        if len(sliding) >= 2:
            ordered = sorted(sliding.items(), key=lambda kv: kv[1])
            (low_s, low_v), (high_s, high_v) = ordered[0], ordered[-1]
            text += f"; {low_s} slides {fmt(high_v / low_v, 2)}× less than {high_s}"
        out.append(text + ".")
    needs = [f"{p['scene']} needs μ ≥ {fmt(p['mu_min'])}" for p in slip.data["panels"]
             if is_finite(p.get("mu_min", math.nan))]
    if needs:
        out.append("Friction needed along the reference trajectory (ref_mu_min): "
                   + "; ".join(needs) + ".")
    return out


def stability_findings(runs, references):
    out = []
    for chart in sel.stability_charts(runs, references):
        cells = [(p["scene"], row, p["values"][j], c) for p in chart["panels"]
                 for (row, j), c in p["cells"].items()]
        numerical = [c for c in cells if c[3]["cls"] == sel.NUMERICAL]
        physical = [c for c in cells if c[3]["cls"] == sel.PHYSICAL]
        unknown = [c for c in cells if c[3]["cls"] == sel.UNKNOWN]
        model = [c for c in cells if c[3]["cls"] == sel.MODEL]
        axis = chart["axis_label"].split(" [")[0]
        text = (f"Stability along {axis} ({chart['group']}): {len(cells)} cells, "
                f"{len(numerical)} numerical failures, {len(physical)} physical")
        if model:
            text += (f", {len(model)} beyond the quasi-static model (stops after "
                     "a motion above the inertia bound)")
        if unknown:
            text += f", {len(unknown)} unclassified"
        if numerical:
            first = {}
            for scene, row, value, _ in numerical:
                key = row.split(" ")[0]
                first.setdefault(key, []).append(value)
            worst = sorted(first.items(), key=lambda kv: (-len(kv[1]), kv[0]))[:3]
            text += "; most numerical failures: " + ", ".join(
                f"{m} ({len(v)})" for m, v in worst)
        out.append(text + ".")
    return out


def stop_location_findings(runs):
    """Per coupling, how far the located physical stops lie from the
    reference's (runs.csv err_stop_t = t_reached − t_ref), and how many lie
    farther than the reference's stop is itself certain (|ref_check_t_diff|,
    its check's stop): a stop one output interval early or late passes the
    same-place verdict, which is two output intervals wide."""
    rows = [r for r in runs if is_finite(r.get("err_stop_t", math.nan))]
    out = []
    for coupling in sorted({r["coupling"] for r in rows}):
        sub = [r for r in rows if r["coupling"] == coupling]
        lags = [r["err_stop_t"] for r in sub]
        span = span_text(lags)
        median = float(np.median(np.abs(lags)))
        text = (f"Located physical stops, {coupling}: {len(sub)} runs stop {span} s "
                f"from the reference's stop (median |difference| {fmt(median)} s)")
        beyond = [r for r in sub if is_finite(r.get("ref_check_t_diff", math.nan))
                  and abs(r["err_stop_t"]) > abs(r["ref_check_t_diff"])]
        if beyond:
            worst = max(beyond, key=lambda r: abs(r["err_stop_t"]))
            lag = " (the hold's lag)" if coupling == "zoh" else ""
            text += (f"; {len(beyond)} differ by more than the reference's own "
                     f"uncertainty (|ref_check_t_diff|), so the difference is the "
                     f"method's{lag}, the largest {worst['method']} on "
                     f"{worst['scene']} ({worst.get('suite_group', '')}): "
                     f"{fmt(worst['err_stop_t'])} s")
        out.append(text + ".")
    return out


# Two events of one wheel and kind closer than this are one event recorded
# twice [s] (the location's brackets are 1e-9 s wide).
EVENT_TWIN_S = 1e-6


def _onto_sample(event, dt):
    """Whether a located event's bracket closes onto an output sample k dt:
    then that sample's own solve decided the event, not the location."""
    if not (is_finite(dt) and dt > 0 and event["located"]):
        return False
    ends = [t for t in (event["t_lower"], event["t_upper"]) if is_finite(t)]
    return any(abs(t - round(t / dt) * dt) <= 1e-12 * max(1.0, abs(t)) for t in ends)


def _event_text(label, found):
    """'<n> <label>, e.g. <run> at <t> s' or ''."""
    if not found:
        return ""
    run, event = found[0]
    return (f"; {len(found)} {label} in {len({r['run_id'] for r, _ in found})} runs, "
            f"e.g. {run['run_id']} wheel {event['wheel']} at {fmt(event['t'], 10)} s")


def event_findings(runs, store):
    """What the located events of the runs (switches/<run_id>.csv) say about
    the location itself: how many were left unlocated (the solves failed
    inside the bracket), one wheel's events of one kind closer than
    EVENT_TWIN_S (one event recorded twice), and brackets that close onto
    an output sample (decided by that sample's solve). Each was once a
    defect of the location (docs/model.md §8.6); none is expected."""
    if store is None:  # no results directory to read them from
        return []
    kinds, files = {}, 0
    unlocated, twins, onto = [], [], []
    for run in runs:
        events = store.switches(run)
        if not events:
            continue
        files += 1
        dt = run.get("dt", math.nan)
        for e in events:
            kinds[e["kind"]] = kinds.get(e["kind"], 0) + 1
            if not e["located"]:
                unlocated.append((run, e))
            elif e["kind"] != "solution_jump" and _onto_sample(e, dt):
                onto.append((run, e))
        by_key = {}
        for e in events:
            by_key.setdefault((e["wheel"], e["kind"]), []).append(e["t"])
        for (wheel, kind), times in by_key.items():
            times.sort()
            for t0, t1 in zip(times, times[1:]):
                if t1 - t0 < EVENT_TWIN_S:
                    twins.append((run, {"wheel": wheel, "t": t0}))
    if not kinds:
        return []
    counts = ", ".join(f"{n} {k.replace('_', ' ')}" for k, n in sorted(kinds.items()))
    problems = (_event_text("not located (their solves failed inside the bracket)",
                            unlocated)
                + _event_text(f"recorded twice (one wheel and kind within {fmt(EVENT_TWIN_S)} s)",
                              twins)
                + _event_text("with a bracket closing onto an output sample (decided by "
                              "that sample's solve, not located)", onto))
    text = f"Located events (switches/<run_id>.csv, {files} runs): {counts} rows"
    text += problems if problems else (
        "; every one located to the switch tolerance, none recorded twice, none "
        "closing onto an output sample")
    return [text + "."]


def _motion_counts(run):
    """Whether a run's qs_inertia_ratio measures the problem's motion: every
    run up to its t_reached, failed ones included, except numerical failures
    (a blow-up's motion is the method's, not the problem's)."""
    return (is_finite(run.get("qs_inertia_ratio", math.nan))
            and sel.failure_cause(run)[0] != sel.NUMERICAL)


def qs_rows(runs, references):
    """[(problem label, scene, n, max ratio, median ratio)] for every problem
    in the results: n counts its runs with a measure (successes and
    non-numerical failures, up to t_reached); a problem without any has
    n = 0 and NaN ratios, so it is named rather than dropped."""
    table = []
    from .problems import group_by_problem
    for _, rows in group_by_problem(runs):
        values = sorted(r["qs_inertia_ratio"] for r in rows if _motion_counts(r))
        table.append((problem_label(rows[0], references), rows[0]["scene"], len(values),
                      values[-1] if values else math.nan,
                      values[len(values) // 2] if values else math.nan))
    if not any(row[2] for row in table):
        return []  # no qs_inertia_ratio column (older results)
    return table


def qs_findings(runs, references, meta):
    rows = qs_rows(runs, references)
    if not rows:
        return []
    threshold, _ = qs_threshold(meta)
    measured = [r for r in rows if r[2]]
    unmeasured = [r for r in rows if not r[2]]
    over = [r for r in measured if r[3] > threshold]
    worst = max(measured, key=lambda r: r[3])
    text = (f"Quasi-static validity over all {len(rows)} problems (failed runs "
            f"up to their stop included, numerical failures not): the largest "
            f"inertial/contact load ratio is {fmt(worst[3])} ({worst[0]}); "
            f"threshold {fmt(threshold)}")
    if over:
        text += (f"; {len(over)} of {len(measured)} measured problems exceed it "
                 "(dynamics matter there: "
                 + ", ".join(r[0] for r in over[:4])
                 + (", ..." if len(over) > 4 else "") + ")")
    else:
        text += f"; all {len(measured)} measured problems are below it"
    if unmeasured:
        text += (f"; {len(unmeasured)} without a measure (every run failed "
                 "numerically or stopped before a second sample): " + ", ".join(r[0] for r in unmeasured[:4])
                 + (", ..." if len(unmeasured) > 4 else ""))
    return [text + "."]


def kkt_findings(runs):
    ok = [r for r in sel.successful(runs) if is_finite(r.get("kkt_residual", math.nan))]
    if not ok:
        return []
    worst = max(ok, key=lambda r: r["kkt_residual"])
    return [f"Verified success: every successful run's NLP solves were checked for "
            f"first-order optimality; the largest KKT residual among them is "
            f"{fmt(worst['kkt_residual'])} ({worst['method']}, {worst['run_id']})."]


EPSILON_GROUP = "epsilon"


def epsilon_findings(runs):
    """The ε ladder (suite group `epsilon`, docs/model.md §7.5): per scene,
    whether it slides (and how the sliding distance converges as ε falls)
    and how closely its creep follows ε."""
    out = []
    rows = [r for r in sel.successful(runs) if r.get("suite_group") == EPSILON_GROUP
            and is_finite(r.get("sliding_distance", math.nan))]
    for scene in sorted({r["scene"] for r in rows}):
        mine = sorted((r for r in rows if r["scene"] == scene), key=lambda r: -r["eps"])
        if len(mine) < 2:
            continue
        eps_text = f"ε {fmt(mine[0]['eps'])} … {fmt(mine[-1]['eps'])} m/s"
        creep_per_eps = [r["creep_distance"] / r["eps"] for r in mine if r["creep_distance"] > 0]
        slides = [r for r in mine if r["sliding_distance"] > 0]
        if not slides:
            text = f"ε ladder on {scene} ({eps_text}): no sliding at any ε"
        else:
            values = ", ".join(fmt(r["sliding_distance"], 5) for r in slides)
            text = (f"ε ladder on {scene} ({eps_text}): sliding distance {values} m "
                    f"as ε falls (slides count once ‖s‖ ≥ 10 ε)")
        if creep_per_eps:
            tail = creep_per_eps[-2:] if slides else creep_per_eps
            spread = max(tail) / min(tail) - 1
            text += (f"; creep {fmt(mine[-1]['creep_distance'])} m at the smallest ε, "
                     f"creep/ε constant within {fmt(100 * spread, 2)} % "
                     f"({'the two smallest ε' if slides else 'every ε'}): the "
                     "regularisation, not physics")
            if slides and spread > 0.05:
                text += ("; the excess is of order ε²: a slide that slows to a stick "
                         "spends its last 10 ε/a seconds below the sliding level "
                         "(docs/model.md §7.5)")
        out.append(text + ".")
    return out


# ------------------------------------------- implicit integrators, coupled mode

COUPLED = "coupled"
# The integrator options the comparisons below vary (docs/harness.md, the
# implicit integrators' option tables): the Newton matrix's Jacobian, exact
# (implicit-function theorem, the default) or by finite differences; the
# linear multistep method and its nonlinear solver.
JACOBIAN, EXACT, FINITE_DIFFERENCE = "jacobian", "ift", "fd"
LMM, NONLINEAR_SOLVER, ADAMS, BDF = "lmm", "nonlinear_solver", "adams", "bdf"
OPTION_WORDS = {LMM: {ADAMS: "Adams", BDF: "BDF"},
                NONLINEAR_SOLVER: {"fixedpoint": "fixed-point"}}
# Grid parameters two runs share to be a matched pair, besides their method
# id (which names every backend option off its default).
MATCH_COLUMNS = ("scene", "terrain", "rk_method", "dt", "tol", "atol", "nlp_tol",
                 "sigma", "eps", "dae_index", "substeps", "contact_check", "mu", "seed",
                 "roughness", "t_end", "scene_fields", "nlp_options", "nlp_max_iter",
                 "locate_events", "event_points", "event_tolerance", "locate_switches")


def _measured(run):
    """(wall, err_pos_rms) of a run, the timing the other findings use; None
    without both (positive, finite)."""
    wall, err = sel.timing(run)[0], run.get("err_pos_rms", math.nan)
    ok = is_finite(wall) and wall > 0 and is_finite(err) and err > 0
    return (wall, err) if ok else None


def _match_key(run, varied):
    """What two runs must share to be compared: the method without the
    options `varied`, and every grid parameter (NaN read as absent)."""
    values = tuple(None if isinstance(v, float) and not math.isfinite(v) else v
                   for v in (run.get(c) for c in MATCH_COLUMNS))
    return (method_without(run["method"], varied),) + values


def matched_pairs(rows, varied, side):
    """{integrator variant: [(a, b)]}: coupled runs of `rows` on side 'a' and
    'b' (side(run), None for neither) that agree on everything but the
    options `varied`, both with a wall time and an error; per matched key
    the first run of each side by run_id. The variant is the integrator with
    its other non-default options, as `variant_label` names it."""
    keys = {}
    for run in rows:
        which = side(run)
        if which and run.get("coupling") == COUPLED and _measured(run):
            keys.setdefault(_match_key(run, varied), {}).setdefault(which, []).append(run)
    groups = {}
    for key in sorted(keys, key=repr):
        found = keys[key]
        if "a" in found and "b" in found:
            first = [min(found[s], key=lambda r: r["run_id"]) for s in ("a", "b")]
            _, _, dae, options, _ = parse_method(key[0])
            groups.setdefault(variant_label(dae, options), []).append(tuple(first))
    return groups


def option_words(options):
    """Integrator options as words: 'BDF, Newton', 'dae_index=1'."""
    words = []
    for name, value in options:
        if name in OPTION_WORDS:
            words.append(OPTION_WORDS[name].get(value, value[:1].upper() + value[1:]))
        else:
            words.append(f"{name}={value}")
    return ", ".join(words)


def variant_label(dae, options):
    listed = option_words(options)
    return f"{dae} ({listed})" if listed else dae


def _median_range(values):
    """('1.3', '1.1–1.5×'): median and range of ratios."""
    values = sorted(values)
    return (fmt(float(np.median(values)), 2),
            f"{fmt(values[0], 2)}–{fmt(values[-1], 2)}×")


def ratio_summary(values, note=""):
    """'1.3× (1.1–1.5× over 6 matched pairs<note>)': median and range of
    per-pair ratios."""
    median, span = _median_range(values)
    spread = f"{span} over {len(values)} matched pairs" if len(values) > 1 \
        else "1 matched pair"
    return f"{median}× ({spread}{note})"


def _jacobian_side(run):
    return {FINITE_DIFFERENCE: "a", EXACT: "b"}.get(dae_option(run, JACOBIAN))


def jacobian_finding(problem):
    """One sentence: per implicit integrator variant, the wall-time ratio
    finite-difference / exact Jacobian over matched pairs and the largest
    relative difference of their errors (to the exact one's); None
    without a matched pair."""
    parts = []
    for label, pairs in sorted(matched_pairs(problem["rows"], {JACOBIAN},
                                             _jacobian_side).items()):
        measured = [(_measured(fd), _measured(ift)) for fd, ift in pairs]
        diff = max(abs(fd[1] - ift[1]) / ift[1] for fd, ift in measured)
        parts.append(f"{label} " + ratio_summary(
            [fd[0] / ift[0] for fd, ift in measured],
            f", position errors differ by ≤ {fmt(100 * diff, 2)} %"))
    if not parts:
        return None
    return (f"Coupled implicit integrators on {problem['label']}, wall time with "
            f"finite-difference over exact (ift) Jacobians: {'; '.join(parts)}.")


def _lmm_side(run):
    lmm = dae_option(run, LMM)
    if lmm == ADAMS:
        return "a"
    return "b" if lmm == BDF and dae_option(run, JACOBIAN) == EXACT else None


def _solver_words(runs):
    values = {dae_option(r, NONLINEAR_SOLVER) for r in runs}
    return "/".join(sorted(option_words([(NONLINEAR_SOLVER, str(v))])
                           for v in values if v is not None))


def lmm_finding(problem):
    """One sentence: per integrator with a choice of linear multistep method,
    Adams over BDF (exact Jacobians) on matched settings: the wall-time and
    error ratios (median, range); None without a matched pair."""
    parts = []
    for label, pairs in sorted(matched_pairs(problem["rows"], {LMM, NONLINEAR_SOLVER},
                                             _lmm_side).items()):
        measured = [(_measured(adams), _measured(bdf)) for adams, bdf in pairs]
        solvers = " vs ".join(_solver_words(p[i] for p in pairs) for i in (0, 1))
        err_median, err_span = _median_range([a[1] / b[1] for a, b in measured])
        parts.append(f"{label}" + (f" ({solvers})" if solvers != " vs " else "")
                     + f" takes {ratio_summary([a[0] / b[0] for a, b in measured])} of "
                     f"BDF's wall time at {err_median}× its position error"
                     + (f" ({err_span})" if len(pairs) > 1 else ""))
    if not parts:
        return None
    return (f"Adams vs BDF (exact Jacobians) on {problem['label']}, coupled: "
            f"{'; '.join(parts)}.")


def implicit_findings(runs, references):
    """Per work-precision problem, the coupled implicit integrators' exact
    vs finite-difference Jacobians and Adams vs BDF, where matched runs
    exist (no sentence otherwise)."""
    out = []
    for problem in sel.work_precision_problems(runs, references):
        out.extend(s for s in (jacobian_finding(problem), lmm_finding(problem)) if s)
    return out


def key_findings(ctx, records):
    return (work_precision_findings(ctx.runs, ctx.references)
            + implicit_findings(ctx.runs, ctx.references) + mu_findings(records)
            + epsilon_findings(ctx.runs)
            + stability_findings(ctx.runs, ctx.references)
            + stop_location_findings(ctx.runs)
            + event_findings(ctx.runs, getattr(ctx, "trajectories", None))
            + qs_findings(ctx.runs, ctx.references, ctx.meta) + kkt_findings(ctx.runs))


def failure_counts(runs):
    counts = {}
    for r in runs:
        if not is_success(r):
            cls = sel.failure_cause(r)[0]
            counts[cls] = counts.get(cls, 0) + 1
    return counts
