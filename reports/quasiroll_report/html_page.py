"""The static, self-contained index.html (no JavaScript)."""

import json
import math
from html import escape

from .data import is_finite
from .plotting import NOT_RUN_COLOUR, fmt, status_colours

MARKER_GLYPHS = {"o": "●", "s": "■", "^": "▲", "D": "◆", "v": "▼", "P": "✚",
                 "X": "✖", "*": "★", "<": "◀", ">": "▶", "h": "⬢", "p": "⬟"}

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


def _swatch(styles, method):
    colour, marker = styles[method]
    return (f'<span class="swatch" style="color:{colour}">'
            f'{MARKER_GLYPHS.get(marker, "●")}</span>')


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


def summary_table(summary, styles, failed_only):
    out = ["<table>", "<tr><th></th><th>method (nlp/dae/coupling)</th><th>runs</th>"
           "<th>status counts</th><th>median wall [s]</th>"
           "<th>median err_pos_rms [m]</th><th>max drift ‖H‖∞</th></tr>"]
    for row in summary:
        counts = ", ".join(f"{escape(s)} {n}" for s, n in
                           sorted(row["status_counts"].items(),
                                  key=lambda kv: (kv[0] != "success", kv[0])))
        note = ' <span class="note">(all runs failed)</span>' \
            if row["method"] in failed_only else ""
        out.append(
            f"<tr><td>{_swatch(styles, row['method'])}</td>"
            f"<td>{escape(row['method'])}{note}</td>"
            f'<td class="num">{row["runs"]}</td><td>{counts}</td>'
            + _num(row["median_wall_s"]) + _num(row["median_err_pos_rms"])
            + _num(row["max_drift"]) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def bands_table(bands, styles):
    if not bands:
        return "<p>No successful run with a finite err_pos_rms.</p>"
    out = ["<table>", "<tr><th>err_pos_rms band [m]</th><th>fastest method</th>"
           "<th>Δt [s]</th><th>tol</th><th>wall [s]</th><th>err_pos_rms [m]</th>"
           "<th>runs in band</th></tr>"]
    for decade, run, count in bands:
        out.append(
            f"<tr><td>[1e{decade}, 1e{decade + 1})</td>"
            f"<td>{_swatch(styles, run['method'])} {escape(run['method'])}</td>"
            + _num(run["dt"]) + _num(run["tol"]) + _num(run["wall_s"])
            + _num(run["err_pos_rms"]) + f'<td class="num">{count}</td></tr>')
    out.append("</table>")
    return "\n".join(out)


def failure_map_table(smap):
    colours = status_colours(smap["statuses"])
    head = "".join(f"<th>{escape(c['group'])}<br>{escape(c['label'])}</th>"
                   for c in smap["columns"])
    out = ['<div class="scroll"><table class="map">', f"<tr><th>method</th>{head}</tr>"]
    for method in smap["methods"]:
        cells = []
        for cell in smap["cells"][method]:
            if cell is None:
                cells.append(f'<td style="background:{NOT_RUN_COLOUR}">–</td>')
                continue
            status, label = cell
            text = "ok" if status == "success" else status + (f" ({label})" if label else "")
            cells.append(f'<td style="background:{colours[status]};color:white">'
                         f"{escape(text)}</td>")
        out.append(f"<tr><th>{escape(method)}</th>{''.join(cells)}</tr>")
    out.append("</table></div>")
    return "\n".join(out)


def figure_block(record):
    return (f'<figure id="{escape(record.name)}">'
            f'<img src="{escape(record.png)}" alt="{escape(record.title)}" '
            f'width="{record.width_px}" height="{record.height_px}">'
            f"<figcaption><b>{escape(record.title)}.</b> {escape(record.caption)} "
            f'[<a href="{escape(record.svg)}">SVG</a>]</figcaption></figure>')


def render_page(ctx, summary, bands, figures, smap, warnings):
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>quasiroll comparison report</title>",
             f"<style>{CSS}</style></head><body>",
             "<h1>quasiroll comparison report</h1>",
             f"<p>{len(ctx.runs)} runs of {len(summary)} methods from "
             f"<code>{escape(ctx.results_dir)}</code>.</p>"]
    if warnings:
        parts.append("<ul>" + "".join(f'<li class="note">{escape(w)}</li>'
                                      for w in warnings) + "</ul>")
    parts += ["<h2>Summary per method</h2>",
              summary_table(summary, ctx.styles, ctx.failed_only),
              "<h2>Fastest method per accuracy band</h2>",
              "<p>Work-precision runs grouped by the decade of their "
              "err_pos_rms; the fastest run in each band.</p>",
              bands_table(bands, ctx.styles),
              "<h2>Run metadata</h2>", metadata_table(ctx.meta),
              "<h2>Figures</h2>",
              "<ul>" + "".join(f'<li><a href="#{escape(f.name)}">{escape(f.title)}</a>'
                               f' (<a href="{escape(f.svg)}">SVG</a>)</li>'
                               for f in figures) + "</ul>"]
    for record in figures:
        if record.name.startswith("fig05"):
            parts.append("<h2>The paper's figures (paper scene, μ = 0.5)</h2>")
        parts.append(figure_block(record))
        if record.name == "fig_failure_map" and smap is not None:
            parts += ["<h3>Failure map as a table</h3>", failure_map_table(smap)]
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
