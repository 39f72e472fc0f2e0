"""Builds the whole report: load, draw every figure, write index.html."""

import json
import os
import sys

from . import figures_methods as fm
from . import figures_paper as fp
from . import problems
from . import selection as sel
from .data import (ReportError, TrajectoryStore, read_meta, read_references,
                   read_runs, read_terrain)
from .findings import key_findings
from .html_page import render_page
from .replay import write_replay
from .plotting import MissingData, apply_style, placeholder_figure

# (figure function, name used for a placeholder), in page order.
FIGURES = [
    (fm.figure_work_precision, "fig_work_precision", "1. Work-precision"),
    (fm.figure_drift, "fig_drift", "2. Constraint drift"),
    (fm.figure_stability, "fig_stability", "3. Stability charts"),
    (fp.figure_snapshots, "fig05_snapshots", "Fig. 5 — the robot on the terrain"),
    (fp.figure_locus, "fig06_locus", "Fig. 6 — contact-point and platform loci"),
    (fp.figure_linear_velocity, "fig07_linear_velocity", "Fig. 7 — platform linear velocity"),
    (fp.figure_angular_velocity, "fig08_angular_velocity", "Fig. 8 — platform angular velocity"),
    (fp.figure_normal_forces, "fig09_normal_forces", "Fig. 9 — normal forces"),
    (fp.figure_longitudinal_traction, "fig10_longitudinal_traction", "Fig. 10 — longitudinal traction"),
    (fp.figure_lateral_traction, "fig11_lateral_traction", "Fig. 11 — lateral traction"),
    (fp.figure_slip, "fig12_slip", "Fig. 12 — slip speeds"),
    (fp.figure_traction_vs_mu, "fig13_traction_vs_mu", "Fig. 13 — traction vs μ"),
    (fp.figure_total_slip_vs_mu, "fig14_total_slip_vs_mu", "Fig. 14 — total slip vs μ"),
    # Fig. 15 compares two methods' drift: drawn with the method figures.
    (fm.figure_stabilisation, "fig15_stabilisation", "Fig. 15 — constraint stabilisation"),
]

FIGURE_NAMES = [name for _, name, _ in FIGURES]


class Context:
    """Everything a figure function needs."""

    def __init__(self, results_dir, out_dir):
        self.results_dir = os.path.abspath(results_dir)
        self.out_dir = out_dir
        self.runs, self.header = read_runs(self.results_dir)
        self.meta = read_meta(self.results_dir)
        problems.use_backends(self.meta)
        self.references = read_references(self.results_dir)
        self.styles = sel.method_styles(self.runs)
        self.failed_only = sel.failed_only_methods(self.runs)
        self.trajectories = TrajectoryStore(self.results_dir)
        self.primary = sel.paper_run(self.runs, self._has_usable_trajectory)
        pvc = sel.pvc_scene(self.runs, self.references)
        self.primary_pvc = (sel.paper_run(self.runs, self._has_usable_trajectory, pvc)
                            if pvc else None)
        # Fig. 5 and the replay: paper and pvc mode from one and the same method.
        self.snapshot_pair = sel.snapshot_pair(self.runs, self._has_usable_trajectory,
                                               pvc, self.primary)
        self._terrains = {}

    def _has_usable_trajectory(self, run):
        return self.trajectories.has(run) and self.trajectories.get(run) is not None

    def terrain_of(self, run):
        """The terrain spec of a run: terrains/<terrain column>.json, else
        terrains/<scene>.json (older results)."""
        spec = self.terrain(run["terrain"]) if run.get("terrain") else None
        return spec if spec is not None else self.terrain(run["scene"])

    def terrain(self, scene):
        if scene not in self._terrains:
            self._terrains[scene] = read_terrain(self.results_dir, scene)
        return self._terrains[scene]


def _draw_figures(ctx, allow_missing, warnings):
    import matplotlib.pyplot as plt
    records = []
    for function, name, title in FIGURES:
        try:
            made = function(ctx)
            records += made if isinstance(made, list) else [made]
        except MissingData as exc:
            plt.close("all")
            if not allow_missing:
                raise
            warnings.append(f"{title}: not drawn ({exc})")
            records.append(placeholder_figure(ctx.out_dir, name, title, str(exc)))
    return records


def _write_manifest(out_dir, records):
    manifest = [{"name": r.name, "title": r.title, "png": r.png, "svg": r.svg,
                 "figsize_in": [r.width_in, r.height_in], "dpi": r.dpi,
                 "width_px": r.width_px, "height_px": r.height_px,
                 "caption": r.caption, "data": r.data}
                for r in records]
    with open(os.path.join(out_dir, "figures.json"), "w", encoding="utf-8") as handle:
        json.dump(manifest, handle, indent=1, default=_jsonable)


def _jsonable(value):
    if isinstance(value, (set, tuple)):
        return list(value)
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def build_report(results_dir, out_dir=None, allow_missing=False):
    """Write the report; return the absolute path of index.html."""
    if not os.path.isdir(results_dir):
        raise ReportError(f"results directory not found: {results_dir}")
    out_dir = os.path.abspath(out_dir or os.path.join(results_dir, "report"))
    if (os.path.isfile(os.path.join(results_dir, "atlas.csv"))
            and not os.path.isfile(os.path.join(results_dir, "runs.csv"))):
        from .atlas import build_atlas_report
        return build_atlas_report(results_dir, out_dir)
    apply_style()
    ctx = Context(results_dir, out_dir)
    if not sel.successful(ctx.runs):
        raise ReportError("runs.csv has no successful run: nothing to plot")
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise ReportError(f"cannot create output directory {out_dir}: {exc}") from None
    warnings = [f"meta.json: {ctx.meta['_warning']}"] if ctx.meta.get("_warning") else []
    if not ctx.meta and not os.path.isfile(os.path.join(ctx.results_dir, "meta.json")):
        warnings.append("meta.json is missing: metadata shown as unknown")
    records = _draw_figures(ctx, allow_missing, warnings)
    replay, notes = write_replay(ctx, list(ctx.snapshot_pair))
    warnings += notes
    page = render_page(ctx, sel.method_summary(ctx.runs),
                       sel.accuracy_bands(ctx.runs, ctx.references), records, warnings,
                       key_findings(ctx, records), replay)
    index = os.path.join(out_dir, "index.html")
    with open(index, "w", encoding="utf-8") as handle:
        handle.write(page)
    _write_manifest(out_dir, records)
    for warning in warnings:
        print(f"make_report: warning: {warning}", file=sys.stderr)
    return index
