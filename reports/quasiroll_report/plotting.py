"""Matplotlib set-up, the fixed style, saving PNG+SVG pairs."""

import math
import os
from dataclasses import dataclass, field

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .data import ReportError  # noqa: E402
from .problems import dae_colour  # noqa: E402

DPI = 100

STYLE = {
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "grid.linestyle": "-",
    "lines.linewidth": 1.4,
    "lines.markersize": 5,
    "figure.dpi": DPI,
    "savefig.dpi": DPI,
    "svg.fonttype": "path",
    "svg.hashsalt": "quasiroll",
    "figure.constrained_layout.use": True,
    "axes.formatter.useoffset": False,
}

# Per-wheel and per-component styles (paper figures show one run, not methods).
WHEEL_STYLES = [("#1b9e77", "-"), ("#d95f02", "--"), ("#7570b3", "-.")]
COMPONENT_STYLES = [("#1b9e77", "-"), ("#d95f02", "--"), ("#7570b3", "-.")]

STATUS_COLOURS = {
    "success": "#2ca02c",
    "INFEASIBLE_FRICTION": "#d62728",
    "LIFT_OFF": "#ff7f0e",
    "DEGENERATE_CONTACT": "#9467bd",
    "SINGULAR": "#8c564b",
    "SOLVER_FAILURE": "#e377c2",
    "step_size_too_small": "#1f77b4",
    "convergence_failure": "#17becf",
    "constraint_failure": "#bcbd22",
    "rhs_failure": "#7f7f7f",
    "invalid_input": "#393b79",
}
_EXTRA_STATUS_COLOURS = ["#843c39", "#637939", "#7b4173", "#3182bd",
                         "#e6550d", "#31a354", "#756bb1", "#636363"]
NOT_RUN_COLOUR = "#f0f0f0"

# Failure causes (docs/harness.md `cause`, `cause_detail`): physical causes in
# cool colours, numerical ones in warm colours, the model's limit
# (quasi_static_invalid) olive, unclassified in grey.
SUCCESS_COLOUR = "#4daf4a"
PHYSICAL_COLOURS = {"friction_limit": "#377eb8", "lift_off": "#80b1d3",
                    "degenerate_contact": "#984ea3"}
PHYSICAL_OTHER = "#bebada"
NUMERICAL_COLOURS = {"step_too_large": "#e41a1c", "baumgarte_instability": "#ff7f00",
                     "solver_failure": "#f781bf", "shared_solver_failure": "#fccde5",
                     "integrator_failure": "#a65628",
                     "drift_blowup": "#fdb462", "gap_blowup": "#b15928",
                     "error": "#333333"}
NUMERICAL_OTHER = "#fb8072"
UNKNOWN_COLOUR = "#9e9e9e"
MODEL_COLOUR = "#8c8c1a"


def integrator_colour(dae):
    """A fixed colour per integrator (problems.dae_colour)."""
    return dae_colour(dae)


def wrap_label(text, width):
    """text in lines of at most `width` characters, broken only after a '/'
    or ',' or at a space (the space dropped), never inside a token: a token
    longer than `width` keeps a line of its own, whole."""
    import re
    lines, line = [], ""
    for piece in re.findall(r"[^/, ]+[/,]?|[/,]| +", text):
        if line and len(line.rstrip()) + len(piece.rstrip()) > width:
            lines.append(line.rstrip())
            line = ""
        if line or not piece.isspace():
            line += piece
    lines.append(line.rstrip())
    return "\n".join(lines)


def cause_colour(cls, detail):
    if cls == "success":
        return SUCCESS_COLOUR
    if cls == "physical":
        return PHYSICAL_COLOURS.get(detail, PHYSICAL_OTHER)
    if cls == "numerical":
        return NUMERICAL_COLOURS.get(detail, NUMERICAL_OTHER)
    if cls == "model":
        return MODEL_COLOUR
    return UNKNOWN_COLOUR


def text_colour(background):
    """Black or white, whichever reads better on the hex colour."""
    r, g, b = (int(background[i:i + 2], 16) / 255 for i in (1, 3, 5))
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.55 else "white"


class MissingData(ReportError):
    """A figure has nothing to draw."""


def apply_style():
    plt.style.use("default")
    plt.rcParams.update(STYLE)


def status_colours(statuses):
    """{status: colour}: fixed colours for known statuses, then extras."""
    colours, extra = {}, 0
    for status in statuses:
        if status in STATUS_COLOURS:
            colours[status] = STATUS_COLOURS[status]
        else:
            colours[status] = _EXTRA_STATUS_COLOURS[extra % len(_EXTRA_STATUS_COLOURS)]
            extra += 1
    return colours


@dataclass
class Figure:
    name: str
    title: str
    caption: str
    width_in: float
    height_in: float
    dpi: int = DPI
    png: str = ""
    svg: str = ""
    notes: list = field(default_factory=list)
    # What the figure drew, for figures.json and the tests (JSON-able).
    data: dict = field(default_factory=dict)

    @property
    def width_px(self):
        return int(round(self.width_in * self.dpi))

    @property
    def height_px(self):
        return int(round(self.height_in * self.dpi))


def new_figure(width_in, height_in, **kwargs):
    return plt.figure(figsize=(width_in, height_in), dpi=DPI, **kwargs)


def save_figure(fig, out_dir, name, title, caption):
    """Write <name>.png and <name>.svg, close the figure, return a Figure."""
    width_in, height_in = fig.get_size_inches()
    record = Figure(name, title, caption, float(width_in), float(height_in))
    record.png = f"{name}.png"
    record.svg = f"{name}.svg"
    fig.savefig(os.path.join(out_dir, record.png), dpi=DPI, format="png",
                metadata={"Software": "quasiroll make_report"})
    fig.savefig(os.path.join(out_dir, record.svg), format="svg",
                metadata={"Date": None})
    plt.close(fig)
    return record


def placeholder_figure(out_dir, name, title, reason):
    fig = new_figure(6, 2.5)
    ax = fig.add_subplot()
    ax.axis("off")
    ax.text(0.5, 0.5, f"{title}\n\nnot drawn: {reason}", ha="center",
            va="center", wrap=True, transform=ax.transAxes)
    return save_figure(fig, out_dir, name, title, f"Not drawn: {reason}.")


def positive(values):
    """Copy of values with non-positive entries replaced by nan (log axes)."""
    values = np.array(values, dtype=float)
    values[~(values > 0)] = np.nan
    return values


def spans_decades(values, decades=1.5):
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values) & (values > 0)]
    if values.size < 2:
        return False
    return math.log10(values.max() / values.min()) >= decades


def legend_below_log_data(ax, values, fontsize=7):
    """Legend of a log-y axes in a band kept free below its data: the lower
    limit is set half the data's span (in decades) under the smallest value,
    so the legend, in the lower third, covers none of the lines."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values) & (values > 0)]
    if values.size:
        lo, hi = float(values.min()), float(values.max())
        span = max(1.0, math.log10(hi / lo))
        ax.set_ylim(lo / 10 ** (0.55 * span), hi * 10 ** (0.05 * span))
    return ax.legend(loc="lower center", fontsize=fontsize)


def points_under_legend(fig, ax):
    """How many of ax's line vertices the legend's box covers (drawn figure
    coordinates): a referee's check that the legend hides no data."""
    legend = ax.get_legend()
    if legend is None:
        return 0
    fig.canvas.draw()
    box = legend.get_window_extent()
    covered = 0
    for line in ax.get_lines():
        xy = np.column_stack([np.asarray(line.get_xdata(), dtype=float),
                              np.asarray(line.get_ydata(), dtype=float)])
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.size == 0:
            continue
        px = ax.transData.transform(xy)
        covered += int(np.sum((px[:, 0] >= box.x0) & (px[:, 0] <= box.x1) &
                              (px[:, 1] >= box.y0) & (px[:, 1] <= box.y1)))
    return covered


def no_data(ax, text="no data"):
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes,
            color="#555555")


def fmt(value, digits=3):
    """Short number for captions: 2.1e-05, 0.31, nan → 'n/a'."""
    if value is None or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "n/a"
    if value != 0 and (abs(value) < 1e-3 or abs(value) >= 1e4):
        return f"{value:.{digits - 1}e}"
    return f"{value:.{digits}g}"


def horizon_text(horizon, template=" over 0–{} s"):
    """The horizon of a μ_min(ref) (the t_end it is maximised over) by
    `template`: ' over 0–20 s'; '' when unknown."""
    ok = isinstance(horizon, (int, float)) and math.isfinite(horizon)
    return template.format(fmt(horizon)) if ok else ""


def span_text(values):
    """'<min> to <max>' of finite values by fmt ('<v>' when they are equal)."""
    lo, hi = min(values), max(values)
    return fmt(lo) if lo == hi else f"{fmt(lo)} to {fmt(hi)}"


def method_label(method):
    return method


def vline_label(ax, x, text, color="#444444", fontsize=7, y=0.97):
    """Label of a vertical marker line at data x: inside the axes (never over
    a panel title), beside the line, clipped to the axes. Rotated along the
    line from `y` (axes fraction) down where the axes are tall enough for
    it, else horizontal at the top. Returns the Text."""
    from matplotlib.transforms import blended_transform_factory
    fig = ax.figure
    height_in = ax.get_position().height * fig.get_figheight()
    rotated = height_in * 72 >= 0.62 * fontsize * (len(text) + 2)
    trans = blended_transform_factory(ax.transData, ax.transAxes)
    return ax.text(x, y, text + " ", rotation=90 if rotated else 0, fontsize=fontsize,
                   ha="right", va="top", color=color, transform=trans, clip_on=True,
                   zorder=30, bbox={"facecolor": "white", "alpha": 0.8,
                                    "edgecolor": "none", "pad": 0.5})
