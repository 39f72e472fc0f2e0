"""Key findings at the top of the page, generated from the data (plain text
sentences with numbers), and the per-problem tables that back them."""

import math

from . import selection as sel
from .data import is_finite, is_success, method_options
from .plotting import fmt
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


def key_findings(ctx, records):
    return (work_precision_findings(ctx.runs, ctx.references) + mu_findings(records)
            + epsilon_findings(ctx.runs)
            + stability_findings(ctx.runs, ctx.references)
            + qs_findings(ctx.runs, ctx.references, ctx.meta) + kkt_findings(ctx.runs))


def failure_counts(runs):
    counts = {}
    for r in runs:
        if not is_success(r):
            cls = sel.failure_cause(r)[0]
            counts[cls] = counts.get(cls, 0) + 1
    return counts
