"""The traversability atlas page: maps of mu_min from DIR/atlas.csv
(`quasiroll atlas`, docs/atlas.md).

Figures (each PNG + SVG):
  atlas_mu_min     mu_min per mode over (x, y) for up to four headings and
                   the minimum over all headings, terrain contours on top;
                   poses where the robot cannot stand are hatched grey
  atlas_pvc_gain   pvc - paper of the minimum over headings
  atlas_fraction   traversable fraction of the poses (x, y, heading) vs mu
  atlas_wheel      critical wheel per mode at the first heading
  atlas_edge       (with DIR/edge.csv) verdicts and median iterations per NLP
                   backend and offset d from the edge
and, when DIR/edge.csv exists, the edge-reliability table per NLP backend.
"""

import csv
import html
import json
import math
import os

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.patches import Patch

from .atlas_view import write_atlas_view
from .data import ReportError
from .plotting import apply_style, new_figure, save_figure
from .terrain import terrain_height

WHEEL_COLOURS = ["#1b9e77", "#d95f02", "#7570b3"]
NOT_STANDING = "#bdbdbd"


def _read_atlas(results_dir):
    path = os.path.join(results_dir, "atlas.csv")
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = list(csv.DictReader(handle))
    except OSError as exc:
        raise ReportError(f"cannot read {path}: {exc}") from None
    if not rows:
        raise ReportError(f"{path} has no rows")
    for r in rows:
        for key in ("x", "y", "heading", "mu_min", "mu", "margin"):
            r[key] = float(r[key])
        r["critical_wheel"] = int(r["critical_wheel"])
    return rows


def _read_json(path):
    try:
        with open(path, encoding="utf-8") as handle:
            return json.load(handle)
    except (OSError, ValueError):
        return None


class Grid:
    """The atlas rows as arrays indexed [mode][heading] -> (ny, nx)."""

    def __init__(self, rows):
        self.xs = sorted({r["x"] for r in rows})
        self.ys = sorted({r["y"] for r in rows})
        self.headings = sorted({r["heading"] for r in rows})
        self.modes = [m for m in ("paper", "pvc") if any(r["mode"] == m for r in rows)]
        shape = (len(self.modes), len(self.headings), len(self.ys), len(self.xs))
        self.mu_min = np.full(shape, np.nan)
        self.wheel = np.zeros(shape, dtype=int)
        self.standing = np.zeros(shape, dtype=bool)
        ix = {v: i for i, v in enumerate(self.xs)}
        iy = {v: i for i, v in enumerate(self.ys)}
        ih = {v: i for i, v in enumerate(self.headings)}
        im = {m: i for i, m in enumerate(self.modes)}
        for r in rows:
            k = (im[r["mode"]], ih[r["heading"]], iy[r["y"]], ix[r["x"]])
            self.standing[k] = r["status"] == "ok"
            if r["status"] == "ok":
                self.mu_min[k] = r["mu_min"]
                self.wheel[k] = r["critical_wheel"]
        self.mu = rows[0]["mu"] if math.isfinite(rows[0]["mu"]) else float("nan")
        self.statuses = {}
        for r in rows:
            key = (r["mode"], r["status"])
            self.statuses[key] = self.statuses.get(key, 0) + 1

    def min_over_headings(self, m):
        with np.errstate(all="ignore"):
            return np.nanmin(np.where(np.isnan(self.mu_min[m]), np.inf,
                                      self.mu_min[m]), axis=0)


def _extent(grid):
    def edges(v):
        if len(v) == 1:
            return v[0] - 0.5, v[0] + 0.5
        h = (v[-1] - v[0]) / (len(v) - 1)
        return v[0] - h / 2, v[-1] + h / 2
    x0, x1 = edges(grid.xs)
    y0, y1 = edges(grid.ys)
    return [x0, x1, y0, y1]


def _contours(ax, grid, terrain):
    if terrain is None or len(grid.xs) < 2 or len(grid.ys) < 2:
        return
    x = np.linspace(grid.xs[0], grid.xs[-1], 120)
    y = np.linspace(grid.ys[0], grid.ys[-1], 120)
    xx, yy = np.meshgrid(x, y)
    try:
        h = terrain_height(terrain, xx, yy)
    except (KeyError, ValueError, TypeError):
        return
    if np.ptp(h) > 0:
        ax.contour(xx, yy, h, levels=8, colors="k", linewidths=0.5, alpha=0.5)


def _map(ax, grid, values, standing, terrain, vmin, vmax, cmap="viridis"):
    ext = _extent(grid)
    ax.imshow(np.where(standing, np.nan, 1.0), origin="lower", extent=ext,
              cmap=ListedColormap([NOT_STANDING]), vmin=0, vmax=1,
              interpolation="nearest", aspect="equal")
    image = ax.imshow(np.where(standing, values, np.nan), origin="lower",
                      extent=ext, cmap=cmap, vmin=vmin, vmax=vmax,
                      interpolation="nearest", aspect="equal")
    _contours(ax, grid, terrain)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(False)
    return image


def _pick_headings(grid, count=4):
    """Up to `count` headings spread over the grid's (indices)."""
    n = len(grid.headings)
    if n <= count:
        return list(range(n))
    return sorted({round(i * n / count) % n for i in range(count)})


def _finite_range(values):
    v = values[np.isfinite(values)]
    if v.size == 0:
        return 0.0, 1.0
    lo, hi = float(v.min()), float(v.max())
    return (lo, hi) if hi > lo else (lo - 0.05, hi + 0.05)


def figure_mu_min(grid, terrain, out_dir):
    picks = _pick_headings(grid)
    cols = len(picks) + 1
    fig = new_figure(2.6 * cols + 0.8, 2.5 * len(grid.modes) + 0.4)
    axes = fig.subplots(len(grid.modes), cols, squeeze=False)
    vmin, vmax = _finite_range(grid.mu_min)
    image = None
    for m, mode in enumerate(grid.modes):
        for c, h in enumerate(picks):
            ax = axes[m][c]
            image = _map(ax, grid, grid.mu_min[m, h], grid.standing[m, h],
                         terrain, vmin, vmax)
            ax.set_title(f"{mode}, heading {math.degrees(grid.headings[h]):.0f}°")
        ax = axes[m][-1]
        best = grid.min_over_headings(m)
        _map(ax, grid, np.where(np.isinf(best), np.nan, best),
             grid.standing[m].any(axis=0), terrain, vmin, vmax)
        ax.set_title(f"{mode}, min over {len(grid.headings)} headings")
    bar = fig.colorbar(image, ax=axes, shrink=0.8, label="mu_min")
    if math.isfinite(grid.mu) and vmin <= grid.mu <= vmax:
        bar.ax.axhline(grid.mu, color="#d62728", linewidth=2)
        bar.ax.text(-0.2, grid.mu, "scene mu", color="#d62728", fontsize=7,
                    va="center", ha="right",
                    transform=bar.ax.get_yaxis_transform())
    caption = (
        "Smallest friction coefficient admitting the commanded quasi-static "
        "motion at each pose (grey: the robot cannot stand there; the cause "
        "is in atlas.csv), one colour scale for all panels; the red mark on "
        "the scale is the scene's mu (above it the robot is stuck). Black "
        "lines: terrain height contours. The last column is the easiest "
        "heading at each position.")
    return save_figure(fig, out_dir, "atlas_mu_min", "mu_min maps", caption)


def figure_pvc_gain(grid, terrain, out_dir):
    if grid.modes != ["paper", "pvc"]:
        return None
    paper, pvc = grid.min_over_headings(0), grid.min_over_headings(1)
    both = np.isfinite(paper) & np.isfinite(pvc)
    diff = np.where(both, pvc - paper, np.nan)
    span = np.nanmax(np.abs(diff)) if both.any() else 1.0
    fig = new_figure(4.2, 3.4)
    ax = fig.add_subplot()
    image = _map(ax, grid, diff, both, terrain, -span, span, cmap="RdBu_r")
    ax.set_title("pvc - paper, min over headings")
    fig.colorbar(image, ax=ax, label="mu_min(pvc) - mu_min(paper)")
    caption = ("Difference of the minimum over headings: red where the "
               "passive variable camber robot needs more friction than the "
               "fully actuated one, blue where it needs less.")
    return save_figure(fig, out_dir, "atlas_pvc_gain", "pvc - paper", caption)


def traversable_fraction(mu_min, mu):
    """Fraction of the poses with mu_min < mu; NaN (cannot stand) counts as
    not traversable."""
    values = np.asarray(mu_min, dtype=float).ravel()
    return float((np.nan_to_num(values, nan=np.inf) < mu).sum()) / values.size


def figure_fraction(grid, out_dir):
    finite = grid.mu_min[np.isfinite(grid.mu_min)]
    top = max(1.0, float(finite.max()) * 1.1) if finite.size else 1.0
    mus = np.linspace(0.0, top, 200)
    fig = new_figure(4.6, 3.2)
    ax = fig.add_subplot()
    for m, mode in enumerate(grid.modes):
        ax.plot(mus, [traversable_fraction(grid.mu_min[m], mu) for mu in mus],
                label=mode)
    if math.isfinite(grid.mu):
        ax.axvline(grid.mu, color="#444444", linestyle=":", linewidth=1)
        ax.annotate(f"scene mu = {grid.mu:g}", (grid.mu, 0.02), fontsize=7,
                    rotation=90, va="bottom", ha="right")
    ax.set_xlabel("friction coefficient mu")
    ax.set_ylabel("traversable fraction of poses")
    ax.set_ylim(0, 1.02)
    ax.legend()
    caption = ("Fraction of all poses (x, y, heading) where the commanded "
               "motion is quasi-statically admissible at friction mu "
               "(mu_min < mu; poses where the robot cannot stand count as "
               "not traversable).")
    return save_figure(fig, out_dir, "atlas_fraction", "traversable fraction vs mu",
                       caption)


def figure_wheel(grid, terrain, out_dir):
    h = 0
    fig = new_figure(3.2 * len(grid.modes) + 0.6, 3.0)
    axes = fig.subplots(1, len(grid.modes), squeeze=False)[0]
    cmap = ListedColormap(WHEEL_COLOURS)
    for m, mode in enumerate(grid.modes):
        wheel = grid.wheel[m, h].astype(float)
        ok = grid.standing[m, h] & (wheel > 0)
        _map(axes[m], grid, wheel, ok, terrain, 0.5, 3.5, cmap=cmap)
        axes[m].set_title(f"{mode}, heading "
                          f"{math.degrees(grid.headings[h]):.0f}°")
    handles = [axes[0].plot([], [], "s", color=c, label=f"wheel {i + 1}")[0]
               for i, c in enumerate(WHEEL_COLOURS)]
    axes[-1].legend(handles=handles, loc="upper right", fontsize=7,
                    framealpha=0.9)
    caption = ("The wheel whose traction ratio sets mu_min (the first to "
               "slip as mu falls) at the first heading of the grid.")
    return save_figure(fig, out_dir, "atlas_wheel", "critical wheel", caption)


def _status_table(grid):
    out = ["<table>", "<tr><th>mode</th><th>status</th><th>poses</th></tr>"]
    for (mode, status), count in sorted(grid.statuses.items()):
        out.append(f"<tr><td>{html.escape(mode)}</td><td>{html.escape(status)}</td>"
                   f'<td class="num">{count}</td></tr>')
    out.append("</table>")
    return "\n".join(out)


EDGE_VERDICTS = ("correct", "wrong_claim", "false_infeasibility", "failure")


def edge_summary(rows):
    """Per (backend, side): verdict counts, backend-detected infeasibility
    below the edge, median iterations and wall time."""
    groups = {}
    for r in rows:
        side = "above" if float(r["offset"]) > 0 else "below"
        groups.setdefault((r["backend"], side), []).append(r)
    out = []
    for (backend, side), group in sorted(groups.items()):
        counts = {v: sum(1 for r in group if r["verdict"] == v) for v in EDGE_VERDICTS}
        detected = sum(1 for r in group if r["nlp_status"] == "infeasible")
        iters = sorted(int(r["iterations"]) for r in group)
        walls = sorted(float(r["wall_s"]) for r in group)
        out.append({"backend": backend, "side": side, "solves": len(group),
                    "counts": counts, "detected": detected,
                    "median_iterations": iters[len(iters) // 2],
                    "median_wall_s": walls[len(walls) // 2]})
    return out


EDGE_COLOURS = {"correct": "#2ca02c", "wrong_claim": "#d62728",
                "false_infeasibility": "#ff7f0e", "failure": "#7f7f7f"}


def _read_edge(results_dir):
    """DIR/edge.csv's rows ([] when there is no edge study)."""
    path = os.path.join(results_dir, "edge.csv")
    if not os.path.isfile(path):
        return []
    with open(path, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def figure_edge(rows, out_dir):
    """Left: per backend and offset d, the verdicts stacked (counts of cells x
    modes); right: median iterations vs d. None without an edge study."""
    if not rows:
        return None
    backends = sorted({r["backend"] for r in rows})
    offsets = sorted({float(r["offset"]) for r in rows}, reverse=True)
    fig = new_figure(12, 4.2)
    ax, ax_it = fig.subplots(1, 2, gridspec_kw={"width_ratios": [2.2, 1]})
    width = 0.8 / len(offsets)
    for b, backend in enumerate(backends):
        mine = [r for r in rows if r["backend"] == backend]
        iterations = []
        for k, d in enumerate(offsets):
            cell = [r for r in mine if float(r["offset"]) == d]
            x = b + (k - (len(offsets) - 1) / 2) * width
            bottom = 0
            for verdict in EDGE_VERDICTS:
                n = sum(1 for r in cell if r["verdict"] == verdict)
                if n:
                    ax.bar(x, n, width * 0.9, bottom=bottom,
                           color=EDGE_COLOURS[verdict])
                    bottom += n
            ax.text(x, bottom, f"{d:+g}", rotation=90, ha="center", va="bottom",
                    fontsize=6)
            its = sorted(int(r["iterations"]) for r in cell)
            iterations.append(its[len(its) // 2] if its else math.nan)
        ax_it.plot(range(len(offsets)), iterations, marker="o", label=backend)
    ax.set_xticks(range(len(backends)))
    ax.set_xticklabels(backends)
    ax.set_ylabel("solves (cells x modes)")
    ax.set_title("verdict per offset d (bar label), mu = mu_min (1 + d)")
    top = max(len([r for r in rows if r["backend"] == b and float(r["offset"]) == d])
              for b in backends for d in offsets)
    ax.set_ylim(0, 1.25 * top)
    ax.legend(handles=[Patch(color=EDGE_COLOURS[v], label=v) for v in EDGE_VERDICTS],
              loc="upper right", fontsize=7, ncol=4)
    ax_it.set_xticks(range(len(offsets)))
    ax_it.set_xticklabels([f"{d:+g}" for d in offsets])
    ax_it.axvline(sum(1 for d in offsets if d > 0) - 0.5, color="k",
                  linestyle=":", linewidth=0.8)
    ax_it.set_xlabel("d (left of the dotted line: above the edge)")
    ax_it.set_ylabel("median iterations")
    ax_it.set_yscale("log")
    ax_it.legend(fontsize=7)
    wrong = sum(1 for r in rows if r["verdict"] == "wrong_claim")
    caption = (f"Solver reliability at the edge: {len(rows)} solves of "
               f"{len({(r['cell'], r['mode']) for r in rows})} (cell, mode) pairs "
               f"by {len(backends)} NLP backends at mu = mu_min (1 + d). Green: "
               "correct (converged above the edge, classified infeasible below "
               "it); red: wrong claim (converged below the edge: "
               f"{wrong} in total); orange: false infeasibility above the edge; "
               "grey: failure. Right: median iterations per offset, showing how "
               "the solves slow down as the problem degenerates at the edge.")
    return save_figure(fig, out_dir, "atlas_edge", "edge reliability", caption)


def _edge_table(rows):
    if not rows:
        return ""
    head = "".join(f"<th>{v}</th>" for v in EDGE_VERDICTS)
    out = ["<h2>Solver reliability at the edge</h2>",
           "<p>Every NLP backend at mu = mu_min (1 + d), d in {+1e-1, +1e-2, "
           "+1e-3} (above: a solution exists) and {-1e-3, -1e-2} (below: "
           "none exists); verdicts in docs/atlas.md. A wrong claim is a "
           "converged solve below the edge.</p>", "<table>",
           f"<tr><th>backend</th><th>side</th><th>solves</th>{head}"
           "<th>said infeasible</th><th>median iterations</th>"
           "<th>median time [ms]</th></tr>"]
    for s in edge_summary(rows):
        cells = "".join(f'<td class="num">{s["counts"][v]}</td>' for v in EDGE_VERDICTS)
        out.append(f"<tr><td>{html.escape(s['backend'])}</td><td>{s['side']}</td>"
                   f'<td class="num">{s["solves"]}</td>{cells}'
                   f'<td class="num">{s["detected"]}</td>'
                   f'<td class="num">{s["median_iterations"]}</td>'
                   f'<td class="num">{1e3 * s["median_wall_s"]:.2f}</td></tr>')
    out.append("</table>")
    return "\n".join(out)


def build_atlas_report(results_dir, out_dir):
    """Write the atlas page; return the absolute path of index.html."""
    apply_style()
    rows = _read_atlas(results_dir)
    grid = Grid(rows)
    meta = _read_json(os.path.join(results_dir, "meta.json")) or {}
    terrain = _read_json(os.path.join(results_dir, "terrain.json"))
    os.makedirs(out_dir, exist_ok=True)
    edge_rows = _read_edge(results_dir)
    records = [figure_mu_min(grid, terrain, out_dir),
               figure_pvc_gain(grid, terrain, out_dir),
               figure_fraction(grid, out_dir),
               figure_wheel(grid, terrain, out_dir),
               figure_edge(edge_rows, out_dir)]
    blocks = []
    for r in records:
        if r is None:
            continue
        blocks.append(f'<figure><img src="{r.png}" alt="{html.escape(r.title)}">'
                      f"<figcaption>{html.escape(r.caption)}</figcaption></figure>")
    view, view_notes = write_atlas_view(grid, terrain, out_dir)
    key = html.escape(str(meta.get("key", "unknown grid")))
    page = ("<!DOCTYPE html><html><head><meta charset=\"utf-8\">"
            "<title>quasiroll traversability atlas</title>"
            "<style>body{font-family:sans-serif;max-width:1200px;margin:auto}"
            "img{max-width:100%}td.num{text-align:right}"
            "table{border-collapse:collapse}td,th{border:1px solid #ccc;"
            "padding:2px 6px}</style></head><body>"
            "<h1>Traversability atlas</h1>"
            f"<p>Grid: <code>{key}</code>; {len(rows)} cells; commit "
            f"{html.escape(str(meta.get('commit', 'unknown')))}; "
            f"{html.escape(str(meta.get('cpu_model', '')))}. How to read the "
            "maps: docs/atlas.md.</p>"
            + _status_table(grid) + "".join(blocks) + view
            + "".join(f"<p><em>{html.escape(n)}</em></p>" for n in view_notes)
            + _edge_table(edge_rows)
            + "</body></html>\n")
    index = os.path.join(out_dir, "index.html")
    with open(index, "w", encoding="utf-8") as handle:
        handle.write(page)
    return os.path.abspath(index)
