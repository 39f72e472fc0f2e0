"""The static, self-contained index.html (no JavaScript of its own; the 3D
replay is a separate page in an iframe)."""

import json
import math
from html import escape

from . import selection as sel
from .data import is_finite
from .findings import qs_rows, qs_threshold
from .plotting import NOT_RUN_COLOUR, cause_colour, fmt, text_colour
from .problems import (dae_marker, nlp_colour, problem_label, problem_sort_key,
                       reference_field)
from .repro import command_lines, copy_inputs, environment

MARKER_GLYPHS = {"o": "●", "s": "■", "^": "▲", "D": "◆", "v": "▼", "P": "✚",
                 "X": "✖", "*": "★", "<": "◀", ">": "▶", "h": "⬢", "p": "⬟"}
# Option variants: the hollow glyph of their pair's marker.
HOLLOW_GLYPHS = {"o": "○", "s": "□", "^": "△", "D": "◇", "v": "▽", "P": "✛",
                 "X": "✕", "*": "☆", "<": "◁", ">": "▷", "h": "⬡", "p": "⬠"}

CSS = """
body { font-family: sans-serif; margin: 1.5em auto; max-width: 1200px;
       color: #222; line-height: 1.4; padding: 0 1em; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.8em 0; font-size: 0.88em; }
th, td { border: 1px solid #ccc; padding: 3px 7px; text-align: left; }
th { background: #f3f3f3; }
td.num { text-align: right; font-family: monospace; }
figure { margin: 1.5em 0; }
figure img { max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { font-size: 0.92em; margin-top: 0.3em; }
.swatch { font-size: 1.2em; }
.note { color: #8a4b00; }
.warn { background: #fff3cd; border: 1px solid #e0b000; padding: 0.5em; }
table.map td { text-align: center; font-size: 0.8em; min-width: 2.5em; }
.scroll { overflow-x: auto; }
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; font-size: 0.85em; }
"""


def _text(value):
    if value is None or value == "" or (isinstance(value, float) and math.isnan(value)):
        return "unknown"
    if isinstance(value, dict):
        return ", ".join(f"{k}: {_text(v)}" for k, v in value.items()) or "unknown"
    if isinstance(value, (list, tuple)):
        return ", ".join(_text(v) for v in value) or "unknown"
    return str(value)


def _num(value, unit=""):
    return f'<td class="num">{escape(fmt(value))}{escape(unit) if is_finite(value) else ""}</td>'


def metadata_table(meta):
    suite = meta.get("suite")
    suite_hash = meta.get("suite_hash")
    if suite_hash is None and isinstance(suite, dict):
        suite_hash = suite.get("hash")  # the harness nests it in "suite"
    rows = [("commit", meta.get("commit")), ("machine", meta.get("machine")),
            ("suite", suite), ("suite hash", suite_hash),
            ("start time", meta.get("start_time")), ("end time", meta.get("end_time"))]
    out = ["<table>"]
    out += [f"<tr><th>{escape(k)}</th><td>{escape(_text(v))}</td></tr>" for k, v in rows]
    versions = meta.get("library_versions", meta.get("libraries"))
    if isinstance(versions, dict) and versions:
        cells = "<br>".join(f"{escape(str(k))} {escape(_text(v))}"
                            for k, v in sorted(versions.items()))
    else:
        cells = escape(_text(versions))
    out.append(f"<tr><th>library versions</th><td>{cells}</td></tr>")
    numerical = meta.get("numerical_libraries")  # absent in older results
    if isinstance(numerical, dict) and numerical:
        cells = "<br>".join(f"{escape(str(k))}: {escape(_text(v))}"
                            for k, v in sorted(numerical.items()))
        out.append(f"<tr><th>BLAS / LAPACK loaded</th><td>{cells}</td></tr>")
    out.append("</table>")
    if meta.get("_warning"):
        out.append(f'<p class="note">{escape(meta["_warning"])}</p>')
    if meta.get("options") is not None:
        out.append("<details open><summary>options</summary><pre>"
                   + escape(json.dumps(meta["options"], indent=2, sort_keys=True,
                                       default=str)) + "</pre></details>")
    return "\n".join(out)


def _style_swatch(style):
    """A MethodStyle in text: glyph (hollow for a variant), underline style."""
    colour, marker, line, face = style
    variant = face != colour
    dash = "solid" if line == "-" else "dotted" if variant else "dashed"
    glyph = (HOLLOW_GLYPHS if variant else MARKER_GLYPHS).get(marker, "○" if variant else "●")
    return (f'<span class="swatch" style="color:{colour};border-bottom:2px {dash} {colour}">'
            f'{glyph}</span>')


def _swatch(styles, method):
    return _style_swatch(styles[method])


def summary_table(summary, styles, failed_only):
    out = ["<table>", "<tr><th></th><th>method (nlp[options]/dae[options]/coupling)</th>"
           "<th>runs</th>"
           "<th>status counts (failures: status (cause class: detail))</th><th>failures: physical / numerical / model / unclassified</th>"
           "<th>max drift ‖H‖∞ (successes)</th>"
           "<th>max drift within the steps, before projection (successes)</th>"
           "<th>max KKT residual (successes)</th></tr>"]
    for row in summary:
        counts = ", ".join(f"{escape(s)} {n}" for s, n in
                           sorted(row["status_causes"].items(),
                                  key=lambda kv: (kv[0] != "success", kv[0])))
        note = ' <span class="note">(all runs failed)</span>' \
            if row["method"] in failed_only else ""
        causes = row["cause_counts"]
        out.append(
            f"<tr><td>{_swatch(styles, row['method'])}</td>"
            f"<td>{escape(row['method'])}{note}</td>"
            f'<td class="num">{row["runs"]}</td><td>{counts}</td>'
            f'<td class="num">{causes.get("physical", 0)} / {causes.get("numerical", 0)}'
            f' / {causes.get("model", 0)} / {causes.get("unknown", 0)}</td>'
            + _num(row["max_drift"]) + _num(row["max_step_drift"]) + _num(row["max_kkt"])
            + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def bands_table(bands, styles):
    if not bands:
        return "<p>No successful work-precision run with a finite err_pos_rms.</p>"
    out = []
    for problem, rows in bands:
        out.append(f"<h3>{escape(problem['label'])}</h3>")
        if not rows:
            out.append("<p>No successful run with a finite err_pos_rms.</p>")
            continue
        out += ["<table>", "<tr><th>err_pos_rms band [m]</th><th>fastest method</th>"
                "<th>Δt [s]</th><th>tol</th><th>wall [s]</th><th>wall spread [s]</th>"
                "<th>wall / simulated s</th><th>err_pos_rms [m]</th><th>runs in band</th></tr>"]
        for decade, run, count in rows:
            wall, low, high = sel.timing(run)
            per = wall / run["t_reached"] if is_finite(run["t_reached"]) and run["t_reached"] > 0 \
                else math.nan
            spread = f"{fmt(low)} – {fmt(high)}" if high > low else "–"
            out.append(
                f"<tr><td>[1e{decade}, 1e{decade + 1})</td>"
                f"<td>{_swatch(styles, run['method'])} {escape(sel.line_key(run))}</td>"
                + _num(run["dt"]) + _num(run["tol"]) + _num(wall)
                + f'<td class="num">{escape(spread)}</td>' + _num(per)
                + _num(run["err_pos_rms"]) + f'<td class="num">{count}</td></tr>')
        out.append("</table>")
    return "\n".join(out)


def recommendation_table(tables, styles):
    """The closing table: per problem, for each decade target E of RMS
    position error, the pair that reaches err <= E fastest."""
    if not tables:
        return "<p>No successful work-precision run: no recommendation.</p>"
    out = []
    for problem, floor, recs in tables:
        out.append(f'<h3 class="recommendation">{escape(problem["label"])}</h3>')
        if is_finite(floor[0]):
            out.append(f'<p class="note">Measured error floor {escape(fmt(floor[0]))} – '
                       f"{escape(fmt(floor[1]))} m (the tightest rungs of "
                       f"{len(floor[2])} best methods); a target below it is reached "
                       "by at most the methods shown.</p>")
        out += ["<table>", "<tr><th>to reach err_pos_rms ≤ E [m]</th><th></th>"
                "<th>fastest pair P</th><th>at Δt [s] / rtol</th><th>err [m]</th>"
                "<th>median time T [s]</th><th>IQR [s]</th><th>timed alone</th>"
                "<th>indistinguishable within the IQR</th></tr>"]
        for k, rec in enumerate(recs):
            nxt = recs[k + 1] if k + 1 < len(recs) else None
            if nxt is not None and nxt["winner"] is not None \
                    and nxt["winner"] is rec["winner"] and nxt["ties"] == rec["ties"]:
                continue  # the same answer for a tighter E: one row for the range
            first = k
            while first > 0 and recs[first - 1]["winner"] is not None \
                    and recs[first - 1]["winner"] is rec["winner"] \
                    and recs[first - 1]["ties"] == rec["ties"]:
                first -= 1
            target = escape(fmt(rec["target"]) if first == k else
                            f"{fmt(recs[first]['target'])} … {fmt(rec['target'])}")
            if rec["winner"] is None:
                out.append(f"<tr><td>{target}</td><td></td><td colspan=\"7\">"
                           "no method reaches it</td></tr>")
                continue
            w = rec["winner"]
            below = is_finite(floor[1]) and rec["target"] < floor[1]
            note = ' <span class="note">(within the floor)</span>' if below else ""
            out.append(
                f"<tr><td>{target}{note}</td><td>{_swatch(styles, w['method'])}</td>"
                f"<td>{escape(rec['line'])}</td><td>{escape(w['label'])}</td>"
                + _num(w["err"]) + _num(w["wall"]) + _num(rec["iqr"])
                + f"<td>{'yes' if w['exclusive'] else 'no'}</td>"
                f"<td>{escape(', '.join(rec['ties']) or '–')}</td></tr>")
        out.append("</table>")
    return "\n".join(out)


def machine_text(meta):
    """The timing machine: CPU model and clock from meta.json's machine."""
    machine = meta.get("machine") if isinstance(meta.get("machine"), dict) else {}
    cpu = machine.get("cpu") or "unknown CPU"
    mhz, max_mhz = machine.get("cpu_mhz"), machine.get("cpu_max_mhz")
    clock = (f"{float(mhz):.0f} MHz" if isinstance(mhz, (int, float)) and is_finite(mhz)
             else "clock unknown")
    if isinstance(max_mhz, (int, float)) and is_finite(max_mhz):
        clock += f" (max {float(max_mhz):.0f} MHz)"
    threads = machine.get("hardware_threads")
    jobs = meta.get("jobs")
    return (f"Timed on {cpu}, {clock}"
            + (f", {threads} hardware threads" if threads else "")
            + (f", --jobs {jobs}" if jobs else "") + ".")


def _reference_method(spec):
    """Human text of a reference's method from its canonical key."""
    kind = spec.get("kind", "")
    if kind.startswith("analytic"):
        return "closed form (" + kind.split(":", 1)[-1] + ")"
    if isinstance(spec.get("method"), str) and spec["method"]:
        # The harness states the method itself (and the check reference's).
        text = spec["method"]
        if isinstance(spec.get("check_method"), str) and spec["check_method"]:
            text += "; checked against " + spec["check_method"]
        return text
    fields = {name: reference_field(spec, name) for name in
              ("dt_divisor", "substeps", "nlp", "residual_tolerance", "coupling",
               "dae", "rk", "dt")}
    try:
        scene_dt = float(fields["dt"])
        out_dt = scene_dt / float(fields["dt_divisor"])
        step = out_dt / float(fields["substeps"])
    except (TypeError, ValueError, ZeroDivisionError):
        out_dt = step = math.nan
    if kind.endswith("dp54"):
        scheme = "DP5(4), rtol 1e-10 / atol 1e-12"
    else:
        scheme = f"{(fields['rk'] or 'rk4').upper()}, step {fmt(step)} s"
    parts = [f"{fields['coupling'] or 'coupled'} {fields['dae'] or '?'}",
             scheme, f"output every {fmt(out_dt)} s",
             f"{fields['nlp'] or '?'} at residual {fields['residual_tolerance'] or '?'}"]
    # (A stated "method" returned above; older caches may carry the rest.)
    for key in ("dt", "tolerance", "check_method", "check_kind"):
        if key in spec and not isinstance(spec[key], (dict, list)):
            parts.append(f"{key} {spec[key]}")
    return "; ".join(parts)


def _reference_stop_cell(spec, run):
    """Why the reference ended (reference_stop: end, physical:<limit>,
    model:breakaway, reference_failure), a reference failure in bold: no run
    is credited with reach past it (docs/harness.md, Reference retries)."""
    stop = spec.get("reference_stop") or run.get("reference_stop", "")
    if not isinstance(stop, str) or not stop:
        return "<td>n/a</td>"
    rescues = spec.get("rescues")
    note = (f" ({int(rescues)} interval{'s' if rescues != 1 else ''} retried)"
            if isinstance(rescues, (int, float)) and not isinstance(rescues, bool)
            and rescues > 0 else "")
    if stop == "reference_failure":
        return f"<td><strong>reference failure</strong>{escape(note)}</td>"
    return f"<td>{escape(stop)}{escape(note)}</td>"


def references_table(ctx):
    used = {}
    for run in ctx.runs:
        if run.get("ref_hash"):
            used.setdefault(run["ref_hash"], run)
    if not used:
        return ('<p class="note">These results name no reference per run (no '
                "<code>ref_hash</code> column): references not listed.</p>")
    has_est = any(is_finite(r.get("ref_err_est", math.nan)) for r in ctx.runs)
    out = []
    if not has_est:
        out.append('<p class="note">No <code>ref_err_est</code> column: the references\' '
                   "own errors were not estimated by this harness version.</p>")
    out += ["<table>", "<tr><th>problem</th><th>reference (ref_hash)</th><th>kind</th>"
            "<th>method</th><th>status</th><th>stop</th><th>t_reached [s]</th>"
            "<th>estimated error [m]</th><th>μ_min along it</th><th>runs</th></tr>"]
    for ref_hash, run in sorted(used.items(), key=lambda kv: problem_sort_key(kv[1])):
        spec = ctx.references.get(ref_hash, {})
        rows = [r for r in ctx.runs if r.get("ref_hash") == ref_hash]
        est = max([r["ref_err_est"] for r in rows if is_finite(r.get("ref_err_est", math.nan))],
                  default=math.nan)
        mu_min = max([r["ref_mu_min"] for r in rows if is_finite(r.get("ref_mu_min", math.nan))],
                     default=math.nan)
        out.append(
            f"<tr><td>{escape(problem_label(run, ctx.references))}</td>"
            f"<td><code>{escape(ref_hash)}</code></td>"
            f"<td>{escape(spec.get('kind', run.get('ref_kind', '')) or 'unknown')}</td>"
            f"<td>{escape(_reference_method(spec) if spec else 'references/' + ref_hash + '.json missing')}</td>"
            f"<td>{escape(str(spec.get('status', run.get('ref_status', ''))))}</td>"
            + _reference_stop_cell(spec, run)
            + _num(float(spec["t_reached"]) if isinstance(spec.get("t_reached"), (int, float))
                   and not isinstance(spec.get("t_reached"), bool)
                   else math.nan) + _num(est) + _num(mu_min)
            + f'<td class="num">{len(rows)}</td></tr>')
    out.append("</table>")
    return "\n".join(out)


def qs_table(ctx):
    rows = qs_rows(ctx.runs, ctx.references)
    threshold, source = qs_threshold(ctx.meta)
    why = (f"<p>Quasi-static validity: <code>qs_inertia_ratio</code> is, over a run, the "
           "largest ratio of the inertial load the quasi-static model neglects "
           "(m|a_com| plus the rotational term) to the contact load it balances "
           f"(docs/model.md §8.8). Threshold {fmt(threshold)} ({escape(source)}): the "
           "neglected inertia perturbs the contact forces, and so μ_min and the "
           "friction-limit conclusions, by about that fraction — 1 % is an order of "
           "magnitude below the friction margins this study resolves (pvc needs "
           "μ ≳ 0.43 on R1 against μ = 0.5); above it the scene needs a dynamic "
           "model. Every problem is listed; its runs count up to their stop, failed "
           "ones included (a stop after such a motion is cause <code>model</code>), "
           "numerical failures not (a blow-up's motion is the method's).</p>")
    if not rows:
        return why + ('<p class="note">No <code>qs_inertia_ratio</code> column in these '
                      "results: validity not shown.</p>")
    out = [why, "<table>", "<tr><th>problem</th><th>runs</th><th>max ratio</th>"
           "<th>median ratio</th><th>verdict</th></tr>"]
    for label, _, count, worst, median in rows:
        if not count:
            verdict = ('<span class="note">no measure: every run failed '
                       "numerically or stopped before a second sample</span>")
        elif worst <= threshold:
            verdict = "quasi-static valid"
        else:
            verdict = '<span class="note">exceeds the threshold: needs dynamics</span>'
        out.append(f"<tr><td>{escape(label)}</td><td class=\"num\">{count}</td>"
                   + _num(worst) + _num(median) + f"<td>{verdict}</td></tr>")
    out.append("</table>")
    return "\n".join(out)


def stability_table(chart):
    out = []
    for panel in chart["panels"]:
        limits = panel.get("limits", [])
        limit = limits[0][0] if len(limits) == 1 else None

        def beyond(value):
            return limit is not None and isinstance(value, float) and value > limit
        head = "".join(
            f'<th title="beyond the RK4 limit σ·h = 2.785">{escape(sel.format_value(v))}*</th>'
            if beyond(v) else f"<th>{escape(sel.format_value(v))}</th>"
            for v in panel["values"])
        out += [f"<p><b>{escape(chart['group'])}</b> — {escape(panel['label'])}</p>",
                '<div class="scroll"><table class="map">',
                f"<tr><th>method \\ {escape(chart['axis_label'])}</th>{head}</tr>"]
        for row in panel["rows"]:
            cells = []
            for j in range(len(panel["values"])):
                cell = panel["cells"].get((row, j))
                if cell is None:
                    cells.append(f'<td style="background:{NOT_RUN_COLOUR}">–</td>')
                    continue
                colour = cause_colour(cell["cls"], cell["detail"])
                what = ("ok" if cell["cls"] == "success" else
                        f"{cell['status']}" if cell["cls"] == "unknown" else
                        f"{cell['cls']}: {cell['detail']}")
                cells.append(f'<td style="background:{colour};color:{text_colour(colour)}" '
                             f'title="{escape(cell["run_id"])}">{escape(what)} '
                             f"{escape(cell['label'])}</td>")
            out.append(f"<tr><th>{escape(row)}</th>{''.join(cells)}</tr>")
        out.append("</table></div>")
        if limit is not None:
            out.append(f'<p class="note">* beyond the fixed-step RK4 stability limit '
                       f"σ·h = 2.785 (h = Δt/{limits[0][1]}: σ·Δt &gt; {limit:g}).</p>")
    return "\n".join(out)


def figure_block(record):
    return (f'<figure id="{escape(record.name)}">'
            f'<img src="{escape(record.png)}" alt="{escape(record.title)}" '
            f'width="{record.width_px}" height="{record.height_px}">'
            f"<figcaption><b>{escape(record.title)}.</b> {escape(record.caption)} "
            f'[<a href="{escape(record.svg)}">SVG</a>]</figcaption></figure>')


def style_key(ctx):
    nlps = sorted({r["nlp"] for r in ctx.runs})
    daes = sorted({r["dae"] for r in ctx.runs})
    parts = [f'<span class="swatch" style="color:{nlp_colour(n)}">■</span> {escape(n)}'
             for n in nlps]
    parts += [f"{MARKER_GLYPHS.get(dae_marker(d), '●')} {escape(d)}" for d in daes]
    return ("<p>Styles in every figure: colour = NLP backend, marker = integrator, "
            "solid line = zoh, dashed = coupled; a method with non-default backend "
            "options (nlp[options]/dae[options]/coupling) has its pair's colour, a "
            "hollow marker and dashes of its own. " + " &nbsp; ".join(parts) + "</p>")


def hosts_note(ctx):
    hosts = sorted({r.get("host", "") for r in ctx.runs if r.get("host")})
    if len(hosts) <= 1:
        return ""
    cpus = sorted({r.get("cpu_model", "") for r in ctx.runs if r.get("cpu_model")})
    return (f'<p class="warn">Mixed hosts: these rows ran on {len(hosts)} machines '
            f"({escape(', '.join(hosts))}; CPUs: {escape(', '.join(cpus) or 'unknown')}). "
            "Wall times of different hosts are not comparable: timing comparisons "
            "below mix machines.</p>")


def repro_section(ctx):
    meta = ctx.meta
    copies = copy_inputs(meta, ctx.results_dir, ctx.out_dir)
    out = ["<p>Commands (from the repository root, after <code>scripts/install-deps.sh"
           "</code> and a Release build):</p>",
           "<pre>" + escape("\n".join(command_lines(meta, ctx.results_dir))) + "</pre>",
           metadata_table(meta), "<table>"]
    out += [f"<tr><th>{escape(k)}</th><td>{escape(v)}</td></tr>" for k, v in environment()]
    out.append("</table>")
    if copies["files"]:
        out.append("<p>Copies of the inputs: " + ", ".join(
            f'<a href="{escape(path)}">{escape(label)}</a>' for label, path in copies["files"])
            + ".</p>")
    for note in copies["notes"]:
        out.append(f'<p class="note">{escape(note)}</p>')
    return "\n".join(out)


def missing_features(ctx):
    """Notes for features the results cannot support (older harness output)."""
    header = set(ctx.header)
    notes = []
    checks = [("wall_s_median", "timing spread (median, min–max error bars): wall times "
               "are the minimum over repeats"),
              ("cause", "failure causes (physical vs numerical): failures are shown "
               "unclassified, in grey, with their status"),
              ("ref_err_est", "the references' estimated errors (no error floor drawn)"),
              ("ref_mu_min", "μ_min of the references (no μ_min line in Figs. 13-14 and "
               "the μ stability chart)"),
              ("qs_inertia_ratio", "quasi-static validity per scene"),
              ("kkt_residual", "verified optimality (KKT residual) of successful runs")]
    for column, what in checks:
        if column not in header:
            notes.append(f"These results have no <code>{column}</code> column "
                         f"(older harness): omitted — {what}.")
    return notes


def render_page(ctx, summary, bands, figures, warnings, findings=(), replay=""):
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>quasiroll comparison report</title>",
             f"<style>{CSS}</style></head><body>",
             "<h1>quasiroll comparison report</h1>",
             f"<p>{len(ctx.runs)} runs of {len(summary)} methods from "
             f"<code>{escape(ctx.results_dir)}</code>. {escape(machine_text(ctx.meta))}"
             "</p>", hosts_note(ctx)]
    if warnings:
        parts.append("<ul>" + "".join(f'<li class="note">{escape(w)}</li>'
                                      for w in warnings) + "</ul>")
    parts += ['<h2 id="findings">Key findings</h2>',
              "<ul>" + "".join(f"<li>{escape(f)}</li>" for f in findings) + "</ul>"
              if findings else "<p>No finding could be computed from these results.</p>"]
    missing = missing_features(ctx)
    if missing:
        parts.append("<ul>" + "".join(f'<li class="note">{m}</li>' for m in missing) + "</ul>")
    parts += [style_key(ctx),
              "<h2>Summary per method</h2>",
              "<p>Counts over every run of the method (all problems); speed and "
              "accuracy are compared per problem below, never pooled.</p>",
              summary_table(summary, ctx.styles, ctx.failed_only),
              "<h2>Fastest method per accuracy band</h2>",
              "<p>Work-precision runs of one problem grouped by the decade of their "
              "err_pos_rms; the fastest run in each band (median wall time over "
              "repeats where recorded, else the minimum).</p>",
              bands_table(bands, ctx.styles),
              '<h2 id="references">References</h2>',
              "<p>Every run is compared with the reference of its problem "
              "(docs/harness.md, References); its estimated error is the largest "
              "position difference to a second reference of a different method "
              "family, the floor below which no run's error is meaningful. "
              "<em>stop</em> says why it ended: <code>end</code>, a physical "
              "limit (<code>physical:&lt;limit&gt;</code>), or a <strong>reference "
              "failure</strong> (its own numerical failure, left after the retry "
              "ladder of docs/harness.md): no run is credited with reach past "
              "a failed reference.</p>",
              references_table(ctx),
              '<h2 id="validity">Quasi-static validity</h2>', qs_table(ctx),
              "<h2>Figures</h2>",
              "<ul>" + "".join(f'<li><a href="#{escape(f.name)}">{escape(f.title)}</a>'
                               f' (<a href="{escape(f.svg)}">SVG</a>)</li>'
                               for f in figures) + "</ul>"]
    for record in figures:
        if record.name.startswith("fig05"):
            parts.append("<h2>The paper's figures (paper scene, μ = 0.5)</h2>")
        parts.append(figure_block(record))
        if record.name.startswith("fig_stability_") and record.notes:
            parts += [f"<details><summary>{escape(record.title)} as a table</summary>",
                      stability_table(record.notes[0]), "</details>"]
    if replay:
        parts += ['<h2 id="replay">3D replay</h2>', replay]
    parts += ['<h2 id="reproduction">Reproduction</h2>', repro_section(ctx)]
    parts += ['<h2 id="recommendation">Recommendation per problem</h2>',
              "<p>To reach an RMS position error E fastest, use pair P: per problem "
              "and decade E, the work-precision point with err_pos_rms ≤ E and the "
              "smallest median wall time over its repeats (T, with its interquartile "
              "range). Pairs whose own fastest point ≤ E is slower by no more than "
              "the larger IQR of the two are listed as indistinguishable. "
              + escape(machine_text(ctx.meta)) + "</p>",
              recommendation_table(sel.recommendation_tables(ctx.runs, ctx.references),
                                   ctx.styles)]
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
