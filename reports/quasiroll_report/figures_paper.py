"""The paper's figures (Figs. 5-15) reproduced from one run of the paper scene
at μ = 0.5, the μ sweep, and a Baumgarte/projection pair."""

import math
import re

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from matplotlib.transforms import blended_transform_factory

from . import selection as sel
from .data import is_finite, is_success
from .plotting import (COMPONENT_STYLES, MissingData, WHEEL_STYLES, fmt, span_text,
                       horizon_text,
                       new_figure, no_data, positive, save_figure,
                       spans_decades, vline_label)
from .figures_methods import COINCIDING_STYLE, coinciding, style_legend_handles
from . import robot
from .problems import (fixed_label, method_style, plot_style, reference_field,
                       robot_geometry, scene_mode)
from .terrain import describe_terrain, terrain_height

WHEELS = (1, 2, 3)
# Each wheel's line colour (WHEEL_STYLES), for its event marks.
WHEEL_COLOURS = {i: colour for i, (colour, _) in zip(WHEELS, WHEEL_STYLES)}


def _run_text(run):
    return (f"run {run['run_id']} ({run['method']}, Δt={fmt(run['dt'])} s, "
            f"μ={fmt(run['mu'])})")


def _primary(ctx):
    if ctx.primary is None:
        raise MissingData(
            "no successful run with a trajectory for the paper figures "
            "(scene 'paper', mu 0.5)")
    return ctx.primary, ctx.trajectories.get(ctx.primary)


def _finite_rows(traj):
    return np.isfinite(traj["c1_x"]) & np.isfinite(traj["c2_x"]) & np.isfinite(traj["c3_x"])


# ---------------------------------------------------------------- Fig. 5

def _terrain_box(traj, margin=0.25):
    xs = np.concatenate([traj[f"c{i}_x"] for i in WHEELS] + [traj["x"]])
    ys = np.concatenate([traj[f"c{i}_y"] for i in WHEELS] + [traj["y"]])
    xs, ys = xs[np.isfinite(xs)], ys[np.isfinite(ys)]
    return (xs.min() - margin, xs.max() + margin, ys.min() - margin,
            ys.max() + margin)


def _terrain_grid(spec, box, n=90):
    gx, gy = np.meshgrid(np.linspace(box[0], box[1], n),
                         np.linspace(box[2], box[3], n))
    return gx, gy, terrain_height(spec, gx, gy)


def _snapshot_indices(traj, count=5):
    rows = np.flatnonzero(_finite_rows(traj))
    if rows.size == 0:
        return []
    picks = np.linspace(0, rows.size - 1, min(count, rows.size))
    return sorted({int(rows[int(round(p))]) for p in picks})


CHASSIS_COLOUR = "#c51b7d"
WHEEL_COLOUR = "#404040"


def _draw_robot(ax, geom, row, alpha=1.0):
    """Chassis (triangle through the three joint mounts, COM post) and the
    three torus wheels at their steer and camber angles."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection
    rot, pos = robot.platform_pose(row)
    mounts = [pos + rot @ b for b in robot.mount_points(geom)]
    plate = Poly3DCollection([mounts], facecolor=CHASSIS_COLOUR, edgecolor="black",
                             alpha=0.85 * alpha, linewidths=0.8, zorder=20)
    ax.add_collection3d(plate)
    for b in mounts:
        ax.plot(*zip(pos, b), color=CHASSIS_COLOUR, linewidth=1.5, zorder=21)
    grid = robot.torus_grid(geom)
    for rot_w, centre in robot.wheel_frames_world(geom, row):
        world = grid @ rot_w.T + centre
        ax.plot_surface(world[..., 0], world[..., 1], world[..., 2], color=WHEEL_COLOUR,
                        alpha=0.9 * alpha, linewidth=0, shade=True, zorder=22)
    ax.scatter([pos[0]], [pos[1]], [pos[2]], color="black", s=10, zorder=23,
               depthshade=False)


def degrees_text(value):
    """An angle in degrees with two significant digits and its sign ('+0.015°',
    '-3.2e-05°'); an exact zero as '0°', never a signed zero."""
    if not math.isfinite(value):
        return "n/a"
    return "0°" if value == 0 else f"{value:+.2g}°"


def _camber_labels(ax, geom, traj, indices):
    """The camber angle δ of each rear wheel (wheels 2, 3) in degrees, written
    above the wheel at the given snapshots (Fig. 5: the last, drawn opaque):
    the wheels are drawn at true scale, so a few degrees of camber would not
    be seen otherwise. Returns the texts."""
    labels = []
    for k in indices:
        row = robot.row_at(traj, k)
        frames = robot.wheel_frames_world(geom, row)
        for i, (_, centre) in zip((2, 3), frames[1:]):
            text = f"δ{i}={degrees_text(math.degrees(float(row[f'delta{i}'])))}"
            ax.text(centre[0], centre[1], centre[2] + 2.2 * geom["R"], text, fontsize=6.5,
                    ha="center", va="bottom", color="#111111", zorder=40,
                    bbox={"facecolor": "white", "alpha": 0.7, "edgecolor": "none",
                          "pad": 0.4})
            labels.append(text)
    return labels


def _snapshot_panel(ax, ctx, run, traj, geom):
    spec = ctx.terrain_of(run)
    ax.computed_zorder = False
    box = _terrain_box(traj, margin=0.3)
    finite = _finite_rows(traj)
    zs = np.concatenate([traj[f"c{i}_z"][finite] for i in WHEELS] + [traj["z"]])
    if spec is not None:
        gx, gy, gz = _terrain_grid(spec, box, 60)
        ax.plot_surface(gx, gy, gz, cmap="gist_earth", alpha=0.6, linewidth=0,
                        antialiased=True, rstride=1, cstride=1, zorder=0)
        zs = np.concatenate([zs, gz.ravel()])
    for i, (wc, _) in zip(WHEELS, WHEEL_STYLES):
        ax.plot(traj[f"c{i}_x"][finite], traj[f"c{i}_y"][finite],
                traj[f"c{i}_z"][finite], color=wc, linewidth=1.2, zorder=5)
    ax.plot(traj["x"], traj["y"], traj["z"], color="black", linewidth=1.0, zorder=5)
    indices = [k for k in _snapshot_indices(traj, 3)
               if robot.finite_pose(robot.row_at(traj, k))]
    for n, k in enumerate(indices):
        _draw_robot(ax, geom, robot.row_at(traj, k), alpha=0.45 + 0.55 * (n + 1) / len(indices))
    camber_labels = _camber_labels(ax, geom, traj, indices[-1:])
    top = float(np.nanmax(traj["z"])) + geom["z_h"]
    low = float(np.nanmin(zs))
    dx, dy, dz = box[1] - box[0], box[3] - box[2], top - low
    ax.set_box_aspect((dx, dy, dz), zoom=1.15)  # true scale: wheels undistorted
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_zlim(low, top)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]", labelpad=-2)
    ax.set_zticks([round(low, 2), round(top, 2)])
    ax.view_init(elev=32, azim=-65)
    cambers = np.concatenate([traj["delta2"][finite], traj["delta3"][finite]])
    cambers = cambers[np.isfinite(cambers)]
    mode = scene_mode(run, ctx.references) or run["scene"]
    ax.set_title(f"{run['scene']} ({mode} mode)\n{run['method']}, Δt={fmt(run['dt'])} s, "
                 f"t_end={fmt(run.get('t_end', math.nan))} s", fontsize=10)
    return {"run": run, "times": [float(traj["t"][k]) for k in indices],
            "camber_labels": camber_labels,
            "max_camber_deg": float(np.degrees(np.max(np.abs(cambers)))) if cambers.size
            else math.nan, "spec": spec}


# Run settings Fig. 5's two panels must share to differ only by the camber
# mode: (runs.csv column, caption name, unit).
_PAIR_SETTINGS = (("t_end", "t_end", " s"), ("dt", "Δt", " s"), ("mu", "μ", ""),
                  ("eps", "ε", " m/s"), ("seed", "seed", ""), ("roughness", "roughness", ""),
                  ("tol", "rtol", ""), ("nlp_tol", "NLP tolerance", ""))


def _setting_text(value, unit):
    if isinstance(value, float):
        return fmt(value) + unit if math.isfinite(value) else "none"
    return f"{value}{unit}" if value not in (None, "") else "none"


def _scene_key(ctx, run):
    """The run's reference key less what is compared apart (mode, μ, ε,
    times) and the reference's own method: robot, mass, gravity, joint
    rates, start, terrain; None without a reference."""
    key = (ctx.references.get(run.get("ref_hash", "")) or {}).get("key", "")
    if not key:
        return None
    return re.sub(r"(?:mode|mu|epsilon)=[^;]*;?|time\{[^}]*\};?", "", key.split("|")[0])


def pair_differences(ctx, paper, pvc):
    """(what differs between Fig. 5's two runs besides their scene name and
    camber mode, the names of what was compared)."""
    diffs, compared = [], ["method"]
    if paper["method"] != pvc["method"]:
        diffs.append(f"method {paper['method']} vs {pvc['method']}")
    for column, name, unit in _PAIR_SETTINGS:
        if column not in paper and column not in pvc:
            continue
        compared.append(name)
        a, b = paper.get(column, math.nan), pvc.get(column, math.nan)
        if not sel.same_value(a, b):
            diffs.append(f"{name} {_setting_text(a, unit)} vs {_setting_text(b, unit)}")
    compared.append("terrain")
    if ctx.terrain_of(paper) != ctx.terrain_of(pvc):
        diffs.append("terrain")
    keys = _scene_key(ctx, paper), _scene_key(ctx, pvc)
    if None not in keys:
        compared.append("robot, mass, gravity, joint rates and start (reference keys)")
        if keys[0] != keys[1]:
            diffs.append("robot, mass, gravity, joint rates or start (reference keys)")
    return diffs, compared


def _pair_sentence(paper, pvc, differences, compared):
    """Fig. 5's claim about its two panels: 'differ only by the camber mode'
    only when nothing compared differs; else the differences."""
    if not differences:
        return (f"Both panels from the same method, {paper['method']} (the method "
                f"both scenes ran at μ = 0.5), with the same {', '.join(compared[1:])}, "
                "so they differ only by the camber mode.")
    start = (f"Both panels from the same method, {paper['method']}, but"
             if paper["method"] == pvc["method"] else
             "The two scenes share no successful method at μ = 0.5, and")
    return (f"{start} the two runs differ in more than the camber mode (the closest "
            f"pair the results hold): paper vs pvc {'; '.join(differences)}.")


def figure_snapshots(ctx):
    _primary(ctx)
    paper, pvc = ctx.snapshot_pair
    pairs = [(paper, ctx.trajectories.get(paper))]
    if pvc is not None:
        pairs.append((pvc, ctx.trajectories.get(pvc)))
    fig = new_figure(7.5 * len(pairs), 4.4)
    panels = []
    for k, (r, t) in enumerate(pairs):
        ax = fig.add_subplot(1, len(pairs), k + 1, projection="3d")
        geom = robot_geometry(ctx.references.get(r.get("ref_hash", "")))
        panels.append(_snapshot_panel(ax, ctx, r, t, geom))
    handles = [Patch(facecolor=CHASSIS_COLOUR, label="chassis (joint mounts, COM)"),
               Patch(facecolor=WHEEL_COLOUR, label="torus wheels (steer, camber)"),
               Line2D([], [], color="black", label="COM path")]
    handles += [Line2D([], [], color=wc, label=f"contact path wheel {i}")
                for i, (wc, _) in zip(WHEELS, WHEEL_STYLES)]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=8, frameon=False)
    parts = []
    for p in panels:
        r = p["run"]
        surface = (describe_terrain(p["spec"]) if p["spec"] is not None
                   else "none (no terrain file: drawn without a terrain surface)")
        parts.append(f"{r['scene']}: {_run_text(r)} at t = "
                     + ", ".join(f"{t:.3g}" for t in p["times"])
                     + f" s, largest camber |δ| {fmt(p['max_camber_deg'], 2)}°, terrain "
                     + surface)
    differences = []
    if pvc is None:
        parts.append("no successful pvc-mode run at μ = 0.5 with a trajectory, so "
                     "only paper mode is shown")
        same = f"Method: {paper['method']}."
    else:
        differences, compared = pair_differences(ctx, paper, pvc)
        same = _pair_sentence(paper, pvc, differences, compared)
    caption = (
        "Fig. 5 — the paper shows the robot crossing the rough terrain R1. "
        "Here the robot itself is drawn at true scale (no vertical exaggeration) "
        "from the trajectory's pose and joint angles: chassis triangle through "
        "the steer and camber joints, the three torus wheels at their steer and "
        "camber angles (each recorded contact point lies on its drawn torus), "
        "faded for earlier times, with the COM and contact paths; paper mode "
        "and passive-variable-camber mode side by side. " + same + " The camber "
        "is to scale, so a few degrees hardly show: each rear wheel is labelled "
        "with its camber angle δ2, δ3 in degrees at the last (opaque) snapshot. "
        + "; ".join(parts) + ".")
    record = save_figure(fig, ctx.out_dir, "fig05_snapshots",
                         "Fig. 5 — the robot on the terrain", caption)
    record.data = {"panels": [{"scene": p["run"]["scene"], "run_id": p["run"]["run_id"],
                               "method": p["run"]["method"], "times": p["times"],
                               "camber_labels": p["camber_labels"]} for p in panels],
                   "differences": differences}
    return record


# ---------------------------------------------------------------- Fig. 6

def figure_locus(ctx):
    run, traj = _primary(ctx)
    spec = ctx.terrain_of(run)
    fig = new_figure(8, 6)
    ax = fig.add_subplot()
    if spec is not None:
        gx, gy, gz = _terrain_grid(spec, _terrain_box(traj), 120)
        filled = ax.contourf(gx, gy, gz, levels=20, cmap="gist_earth", alpha=0.45)
        fig.colorbar(filled, ax=ax, label="terrain height h [m]", shrink=0.8)
    # The centre path first and thin, the contact paths over it: wheel 1's
    # runs along it (it was hidden under a thicker centre line).
    ax.plot(traj["x"], traj["y"], color="black", linewidth=0.9, zorder=2,
            label="platform centre")
    for i, (colour, style) in zip(WHEELS, WHEEL_STYLES):
        ax.plot(traj[f"c{i}_x"], traj[f"c{i}_y"], color=colour, linestyle=style,
                linewidth=1.8, zorder=3, label=f"contact point wheel {i}")
    ax.plot(traj["x"][0], traj["y"][0], "ko", label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="best")
    ok = np.isfinite(traj["x"]) & np.isfinite(traj["y"])
    path = float(np.sum(np.hypot(np.diff(traj["x"][ok]), np.diff(traj["y"][ok]))))
    lateral = float(np.nanmax(np.abs(traj["y"] - traj["y"][0])))
    caption = (
        "Fig. 6 — the paper shows the loci of the three contact points and of "
        "the platform centre in the x-y plane. This run: platform centre path "
        f"length {fmt(path)} m, largest lateral deviation {fmt(lateral)} m "
        f"({_run_text(run)}).")
    return save_figure(fig, ctx.out_dir, "fig06_locus",
                       "Fig. 6 — contact-point and platform loci", caption)


# ------------------------------------------------------------ Figs. 7-12

def _time_series_figure(series, ylabel):
    """A figure of several named series against t (one run)."""
    fig = new_figure(8, 4.2)
    ax = fig.add_subplot()
    for (label, t, values), (colour, style) in zip(series, COMPONENT_STYLES):
        ax.plot(t, values, color=colour, linestyle=style, label=label)
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    ax.legend(loc="best")
    return fig


def _extremes(traj, columns):
    values = np.concatenate([traj[c] for c in columns])
    values = values[np.isfinite(values)]
    if values.size == 0:
        return math.nan, math.nan
    return float(values.min()), float(values.max())


def figure_linear_velocity(ctx):
    run, traj = _primary(ctx)
    cols = ["vx", "vy", "vz"]
    fig = _time_series_figure([(f"{c} (world)", traj["t"], traj[c]) for c in cols],
                              "platform linear velocity [m/s]")
    speed = np.hypot(np.hypot(traj["vx"], traj["vy"]), traj["vz"])
    caption = (
        "Fig. 7 — the paper shows the platform's linear velocity components "
        "over the traverse. This run: mean speed "
        f"{fmt(float(np.nanmean(speed)))} m/s, vz within "
        f"[{', '.join(fmt(v) for v in _extremes(traj, ['vz']))}] m/s "
        f"({_run_text(run)}).")
    return save_figure(fig, ctx.out_dir, "fig07_linear_velocity",
                       "Fig. 7 — platform linear velocity", caption)


def figure_angular_velocity(ctx):
    run, traj = _primary(ctx)
    cols = ["wx", "wy", "wz"]
    fig = _time_series_figure([(f"{c} (world)", traj["t"], traj[c]) for c in cols],
                              "platform angular velocity [rad/s]")
    peak = max(abs(v) for v in _extremes(traj, cols)) if np.any(
        np.isfinite(traj["wx"])) else math.nan
    caption = (
        "Fig. 8 — the paper shows the platform's angular velocity components, "
        "excited by the terrain bumps. This run: peak |ω| component "
        f"{fmt(peak)} rad/s ({_run_text(run)}).")
    return save_figure(fig, ctx.out_dir, "fig08_angular_velocity",
                       "Fig. 8 — platform angular velocity", caption)


# A step over one sample interval is a jump when it exceeds this many times
# the median step of the intervals around it (_is_jump).
JUMP_RATIO = 8.0


def _event_spans(events):
    """[(lo, hi, always)]: where a plotted value may change within one sample
    interval at the run's located events (switches/<run_id>.csv): each
    event's bracket [t_lower, t_upper] (always = a solution jump: the whole
    solution jumps there), and each wheel's stick window, from its
    slide→stick to its next stick→slide switch (a slip reversing inside
    turns the tractions, docs/model.md §8.6, Reversals)."""
    spans, stuck = [], {}
    for e in sorted(events, key=lambda e: e["t"]):
        lo = e["t_lower"] if is_finite(e["t_lower"]) else e["t"]
        hi = e["t_upper"] if is_finite(e["t_upper"]) else e["t"]
        spans.append((lo, hi, e["kind"] == "solution_jump"))
        if e["kind"] == "switch" and e["to"] == "stick":
            stuck[e["wheel"]] = lo
        elif e["kind"] == "switch" and e["to"] == "slide" and e["wheel"] in stuck:
            spans.append((stuck.pop(e["wheel"]), hi, False))
    return spans


def _is_jump(steps, k, floor):
    """Whether |step k| (sample k → k+1) is a jump: above floor and JUMP_RATIO
    times the median |step| two to four intervals away on either side (the
    adjacent ones left out: a jump may be split over two intervals)."""
    step = steps[k]
    around = [steps[j] for j in (k - 4, k - 3, k - 2, k + 2, k + 3, k + 4)
              if 0 <= j < steps.size and math.isfinite(steps[j])]
    if not math.isfinite(step) or step <= floor:
        return False
    return step > JUMP_RATIO * (float(np.median(around)) if around else 0.0)


def break_cuts(t, values, spans):
    """Sample intervals k (t_k → t_k+1) where the line of values is broken:
    those that overlap a span of _event_spans and where values jump
    (_is_jump; floor 1e-3 of the values' range), and every one that holds a
    solution jump."""
    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float)
    steps = np.abs(np.diff(values))
    finite = values[np.isfinite(values)]
    floor = 1e-3 * float(np.ptp(finite)) if finite.size else 0.0
    cuts = set()
    for lo, hi, always in spans:
        first = max(int(np.searchsorted(t, lo, side="right")) - 1, 0)
        last = min(int(np.searchsorted(t, hi, side="left")), t.size - 1)
        cuts.update(k for k in range(first, last) if always or _is_jump(steps, k, floor))
    return sorted(cuts)


def with_breaks(t, values, cuts):
    """(t, values) with a nan inserted inside each cut interval: the line
    stops at the sample before and resumes at the one after."""
    t = np.asarray(t, dtype=float)
    values = np.asarray(values, dtype=float)
    if not cuts:
        return t, values
    at = np.asarray(cuts) + 1
    return (np.insert(t, at, 0.5 * (t[at - 1] + t[at])), np.insert(values, at, np.nan))


def between_breaks(cuts):
    """Samples with a cut on both sides: inside a transition (drawn as dots,
    left out of the caption's extremes)."""
    cut = set(cuts)
    return np.array(sorted(k + 1 for k in cut if k + 1 in cut), dtype=int)


def _creep_level(run):
    """10 ε: a wheel slipping slower creeps (docs/model.md §7.5); nan without
    a finite ε. Figs. 10-12 mark creep by it."""
    eps = run.get("eps", math.nan)
    return 10 * eps if is_finite(eps) and eps > 0 else math.nan


CREEP_UNDERLAY = "#b8b8b8"


def _wheel_series(traj, column, total, absolute):
    """[(label, colour, style, width, values, wheel)] of the wheels' columns,
    then their sum labelled `total` (wheel None) if given."""
    series = [(f"wheel {i}", colour, style, 1.4, np.asarray(traj[column.format(i=i)], float), i)
              for i, (colour, style) in zip(WHEELS, WHEEL_STYLES)]
    if total:
        series.append((total, "black", ":", 1.0, sum(s[4] for s in series), None))
    return [(label, colour, style, width, np.abs(values) if absolute else values, wheel)
            for label, colour, style, width, values, wheel in series]


def _wheel_figure(ctx, column, ylabel, total=None, log=False, absolute=False,
                  creep=False):
    """One line per wheel of column.format(i=i) against t (and their sum,
    labelled `total`), each broken where it jumps at a located event
    (break_cuts), a sample between two breaks drawn as a dot; with creep a
    grey underlay where the wheel creeps (‖s_i‖ < 10 ε). Returns (fig, ax,
    facts): the wheels' values outside transitions ("kept"), the times of
    the samples inside one ("inside"), the number of breaks, the sum."""
    run, traj = _primary(ctx)
    spans = _event_spans(ctx.trajectories.switches(run) or [])
    t = np.asarray(traj["t"], dtype=float)
    level = _creep_level(run) if creep else math.nan
    fig = new_figure(8, 4.2)
    ax = fig.add_subplot()
    facts = {"kept": [], "inside": set(), "breaks": 0, "sum": None, "creep": {}}
    for label, colour, style, width, values, wheel in _wheel_series(traj, column, total,
                                                                    absolute):
        cuts = break_cuts(t, values, spans)
        inside = between_breaks(cuts)
        drawn = positive(values) if log else values
        ax.plot(*with_breaks(t, drawn, cuts), color=colour, linestyle=style,
                linewidth=width, label=label, zorder=3)
        if inside.size:
            ax.plot(t[inside], drawn[inside], linestyle="none", marker="o",
                    markersize=2.5, color=colour, zorder=3)
        facts["breaks"] += len(cuts)
        if wheel is None:
            facts["sum"] = values
            continue
        keep = np.ones(t.size, dtype=bool)
        keep[inside] = False
        facts["kept"].append(values[keep])
        facts["inside"].update(float(t[k]) for k in inside)
        if is_finite(level):
            creeping = np.asarray(traj[f"slip{wheel}"], dtype=float) < level
            facts["creep"][wheel] = float(np.mean(creeping))
            ax.plot(*with_breaks(t, np.where(creeping, values, np.nan), cuts),
                    color=CREEP_UNDERLAY, linewidth=5, alpha=0.7, zorder=1,
                    solid_capstyle="butt")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    return fig, ax, facts


def _sample_extremes(facts):
    kept = np.concatenate(facts["kept"]) if facts["kept"] else np.array([])
    kept = kept[np.isfinite(kept)]
    return (float(kept.min()), float(kept.max())) if kept.size else (math.nan, math.nan)


def _range_text(facts, run, unit):
    """'This run: the samples range over [a, b] <unit> over the three
    wheels', leaving out the samples inside a transition (and saying so)."""
    low, high = _sample_extremes(facts)
    inside = sorted(facts["inside"])
    left_out = ""
    if inside:
        left_out = (f", leaving out {len(inside)} sample(s) that fall inside a "
                    "transition (between two breaks, drawn as dots) at t = "
                    + ", ".join(f"{fmt(x, 5)}" for x in inside[:6]) + " s")
    return (f" This run: the output samples range over [{fmt(low)}, {fmt(high)}] {unit} "
            f"over the three wheels{left_out} ({_run_text(run)}).")


def _finish_legend(ax, handles=(), labels=()):
    """The axes' own entries, then the given ones, right of the axes: with
    the event kinds and the creep marks there are too many to sit on the data."""
    own_handles, own_labels = ax.get_legend_handles_labels()
    ax.legend(list(own_handles) + list(handles), list(own_labels) + list(labels),
              loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
              fontsize=7)


# The per-wheel force figures: (file stem, title, column, y label, what the
# paper shows, which force).
_WHEEL_FORCE_FIGURES = {
    "normal_forces": (
        "fig09_normal_forces", "Fig. 9 — normal forces", "n{i}",
        "normal force N_i [N]",
        "Fig. 9 — the paper shows the three normal forces redistributing as "
        "the wheels cross the bumps, their sum balancing the weight.", "normal"),
    "longitudinal_traction": (
        "fig10_longitudinal_traction", "Fig. 10 — longitudinal traction",
        "t{i}_lon", "longitudinal traction [N]",
        "Fig. 10 — the paper shows the longitudinal traction of each wheel as "
        "the robot climbs and descends the bumps.", "longitudinal"),
    "lateral_traction": (
        "fig11_lateral_traction", "Fig. 11 — lateral traction", "t{i}_lat",
        "lateral traction [N]",
        "Fig. 11 — the paper shows the lateral traction that keeps the wheels "
        "from side-slipping on the sloped terrain.", "lateral"),
}


# Vertical event lines: kind -> (legend label, dash pattern), none of them
# shaped like a wheel's (WHEEL_STYLES: solid, dashed, dash-dotted): dotted,
# dash-dot-dotted, long and short dashes.
_EVENT_LINES = {"switch": ("stick/slide switch", (0, (1, 2))),
                "creep_reversal": ("creep reversal", (0, (5, 1.5, 1, 1.5, 1, 1.5))),
                "solution_jump": ("solution jump", (0, (8, 2, 3, 2)))}
# Their codes in the labels along the top edge (+ the wheel).
_EVENT_CODES = {"switch": "S", "creep_reversal": "R", "solution_jump": "J"}


def _jump_lines(jumps):
    """One line per solution jump time: a jump is the whole solution's (one
    entry per wheel, one bracket), drawn black, not overdrawn in the wheels'
    colours."""
    return [{"t": t, "wheel": None} for t in sorted({e["t"] for e in jumps})]


def _jump_sentence(jump_lines):
    if not jump_lines:
        return ""
    return (f" Dashed black: {len(jump_lines)} solution jump(s) (long and short "
            "dashes), where "
            "the root the run followed ends in a fold and the slips of all wheels "
            "jump to another root (docs/model.md §8.6; in the limit ε → 0 a "
            "wheel starts to slide there): "
            + ", ".join(f"{fmt(e['t'], 5)} s" for e in jump_lines[:8]) + ".")


def label_groups(items, px_per_unit, line_px=11.0):
    """[(t, text)] in groups whose labels, one line each along the top edge,
    would overlap (closer than their lines' width, line_px pixels each):
    such labels share one tick."""
    groups = []
    for item in sorted(items):
        groups.append([item])
        while len(groups) > 1:
            a, b = groups[-2], groups[-1]
            gap = (np.mean([x for x, _ in b]) - np.mean([x for x, _ in a])) * px_per_unit
            if gap >= line_px * (len(a) + len(b)) / 2 + 2:
                break
            groups[-2:] = [a + b]
    return groups


def _label_events(ax, items):
    """Each event's time (5 significant digits) and code along the top edge,
    rotated; labels that would overlap share one tick, one line each.
    Returns the tick texts."""
    if not items:
        return []
    low, high = ax.get_xlim()
    fig = ax.figure
    width_px = ax.get_position().width * fig.get_figwidth() * fig.dpi
    groups = label_groups(items, width_px / max(high - low, 1e-12))
    top = ax.secondary_xaxis("top")
    texts = ["\n".join(text for _, text in g) for g in groups]
    top.set_xticks([float(np.mean([x for x, _ in g])) for g in groups], texts)
    top.tick_params(axis="x", labelsize=6, labelrotation=90, pad=1, length=3)
    return texts


def _draw_events(ax, events):
    """The located events as verticals in their own styles (_EVENT_LINES):
    switches and creep reversals in the wheel's colour, a solution jump once
    in black; labelled along the top edge. Returns (legend handles, labels,
    {kind: drawn events}, the top labels)."""
    drawn = {"switch": [e for e in events if e["kind"] == "switch"],
             "creep_reversal": [e for e in events if e["kind"] == "creep_reversal"],
             "solution_jump": _jump_lines([e for e in events
                                           if e["kind"] == "solution_jump"])}
    handles, labels, items = [], [], []
    for kind, lines in drawn.items():
        label, style = _EVENT_LINES[kind]
        for e in lines:
            ax.axvline(e["t"], color=WHEEL_COLOURS.get(e["wheel"], "black"), linestyle=style,
                       linewidth=0.8, alpha=0.8, zorder=2)
            items.append((e["t"], f"{fmt(e['t'], 5)} {_EVENT_CODES[kind]}{e['wheel'] or ''}"))
        if lines:
            handles.append(Line2D([], [], linestyle=style, linewidth=0.8,
                                  color="black" if kind == "solution_jump" else "grey"))
            labels.append(label)
    return handles, labels, drawn, _label_events(ax, items)


def _mark_switches(ctx, run, ax):
    """Vertical lines at the run's located events (_draw_events); (the
    caption's sentences about them, legend handles, labels, drawn events)."""
    events = ctx.trajectories.switches(run)
    if events is None:
        return (" The run's switch times are not in the results "
                "(no switches/ file), so none are marked.", [], [],
                {"switch": [], "creep_reversal": [], "solution_jump": []})
    handles, labels, drawn, _ = _draw_events(ax, events)
    switches, reversals = drawn["switch"], drawn["creep_reversal"]
    turns = ""
    if reversals:
        turns = (f" Dash-dotted: the {len(reversals)} creep reversal(s) (dash-dot-dot, "
                 "in the wheel's colour), a creeping wheel's slip reversing, where "
                 "the tractions turn within a time proportional to ε (docs/model.md "
                 "§8.6): " + ", ".join(f"{fmt(e['t'], 5)} s (wheel {e['wheel']})"
                                       for e in reversals[:8]) + ".")
    turns += _jump_sentence(drawn["solution_jump"])
    if drawn["switch"] or reversals or drawn["solution_jump"]:
        turns += (" Along the top edge each event's located time (5 significant "
                  "digits) with S<i> a stick/slide switch of wheel i, R<i> a creep "
                  "reversal, J a solution jump; events too close to label apart "
                  "share one tick, one line each.")
    if not switches:
        text = (" No wheel changed between sticking and sliding in this run "
                "(switch location on)." + turns
                if run.get("locate_switches") != "false"
                else " Switch location was off for this run.")
        return text, handles, labels, drawn
    located = sum(1 for e in switches if e["located"])
    listed = ", ".join(
        f"{fmt(e['t'], 5)} s (wheel {e['wheel']} {e['from']}→{e['to']})"
        for e in switches[:8])
    more = f" and {len(switches) - 8} more" if len(switches) > 8 else ""
    return (f" Dotted verticals, in the wheel's colour: the {len(switches)} "
            f"stick/slide switches of this run ({located} located to the "
            f"switch tolerance where a wheel's friction margin crosses 5e-5, "
            f"docs/model.md §8.6; a wheel that reaches its cone slowly starts "
            f"to slide later than that, at a solution jump where there is "
            f"one): {listed}{more}." + turns), handles, labels, drawn


def _breaks_text(run, facts):
    return (f" Lines join the output samples (Δt = {fmt(run['dt'])} s) except at "
            f"{facts['breaks']} break(s): where a value jumps within a sample "
            "interval that holds a located event's bracket or lies in a wheel's "
            "stick window (slide→stick to stick→slide), or holds a solution jump, "
            "the line stops at the sample before and resumes at the one after; "
            "a steep but continuous change elsewhere (the tractions' turns, whose "
            "width is proportional to ε, docs/model.md §8.6) still shows as a "
            "slope between two samples.")


def _weight(ctx, run):
    """m g [N] from the run's reference key (the scene's mass and gravity),
    nan without one."""
    reference = ctx.references.get(run.get("ref_hash", ""))
    try:
        return (float(reference_field(reference, "mass"))
                * float(reference_field(reference, "gravity")))
    except ValueError:
        return math.nan


def vertical_force_sum(ctx, run, traj):
    """Σ_i F_i·e_z per sample, F_i = N n_g + t_lon l + t_lat n_g × l
    (robot.contact_force_world, docs/model.md §7.6) with n_g the terrain
    normal at the contact; None without the terrain."""
    spec = ctx.terrain_of(run)
    if spec is None:
        return None
    geom = robot_geometry(ctx.references.get(run.get("ref_hash", "")))
    total = np.full(len(traj["t"]), np.nan)
    for k in range(total.size):
        row = robot.row_at(traj, k)
        if not robot.finite_pose(row):
            continue
        total[k] = sum(robot.contact_force_world(
            rot_w, robot.terrain_normal(spec, row[f"c{i}_x"], row[f"c{i}_y"],
                                        terrain_height),
            row[f"n{i}"], row[f"t{i}_lon"], row[f"t{i}_lat"])[2]
            for i, (rot_w, _) in zip(WHEELS, robot.wheel_frames_world(geom, row)))
    return total


def _weight_text(ctx, run, traj, ax, facts):
    """Draws m g (grey) and says how Σ N_i and the contact forces' vertical
    components compare with it."""
    weight = _weight(ctx, run)
    summed = facts["sum"][np.isfinite(facts["sum"])]
    span = f"[{fmt(float(summed.min()))}, {fmt(float(summed.max()))}] N" if summed.size \
        else "n/a"
    if not is_finite(weight):
        return (f" Σ N_i (black dotted) ranges over {span}; the weight m g is not "
                "drawn (no reference key with the scene's mass and gravity).")
    ax.axhline(weight, color="grey", linewidth=1.0, zorder=2, label=f"m g = {fmt(weight)} N")
    text = (f" Grey: the weight m g = {fmt(weight)} N (mass and gravity from the "
            f"scene's reference key). Σ N_i (black dotted) ranges over {span}: it "
            "is not m g, because on the slopes the normals tilt and the "
            "tractions have vertical components")
    vertical = vertical_force_sum(ctx, run, traj)
    if vertical is None or not np.any(np.isfinite(vertical)):
        return text + " (not computed here: no terrain file)."
    off = float(np.nanmax(np.abs(vertical - weight)))
    return text + (f"; the vertical components of the contact forces, Σ_i F_i·e_z "
                   "with F_i = N_i n_g + t_lon l + t_lat n_g × l (docs/model.md §7.6, "
                   f"n_g the terrain normal at the contact), balance m g within "
                   f"{fmt(off)} N.")


def _traction_text(ctx, run, traj, column, facts, net):
    """What the per-wheel tractions are in this mode: in paper mode internal
    (antagonistic) forces that scale with μ and, for creeping wheels, are
    fixed by the creep regularisation; the net (with net) and creep shares."""
    values = np.array([traj[column.format(i=i)] for i in WHEELS], dtype=float)
    ok = np.all(np.isfinite(values), axis=0)
    values = values[:, ok]
    mode = scene_mode(run, ctx.references) or run["scene"]
    if mode == "pvc":
        return (" In pvc mode the statics are determinate (docs/model.md §7.5): "
                "the tractions follow from the loads, not from the regularisation.")
    opposed = float(np.mean((values.min(axis=0) < 0) & (values.max(axis=0) > 0))) \
        if values.size else math.nan
    text = (" In paper mode the robot is over-actuated (docs/model.md §7.5): the "
            "per-wheel tractions include internal, antagonistic forces — the wheels "
            f"pull against each other (signs differ) in {fmt(100 * opposed)} % "
            "of the samples — which scale with μ, and a creeping wheel's traction "
            "is statically indeterminate, fixed by the creep regularisation (its "
            "slip in units of ε), not by the terrain.")
    if net and values.size:
        total = values.sum(axis=0)
        text += (f" Their sum (black dotted, the net traction) stays within "
                 f"[{fmt(float(total.min()))}, {fmt(float(total.max()))}] N while "
                 f"single wheels reach {fmt(float(np.abs(values).max()))} N.")
    if facts["creep"]:
        text += (f" Grey underlay: the wheel creeps (‖s_i‖ < 10 ε = "
                 f"{fmt(_creep_level(run))} m/s, as in Fig. 12): "
                 + ", ".join(f"wheel {i} {fmt(100 * share)} %"
                             for i, share in sorted(facts["creep"].items()))
                 + " of the samples.")
    return text


def _wheel_force_figure(ctx, name):
    stem, title, column, ylabel, paper_text, force = _WHEEL_FORCE_FIGURES[name]
    run, traj = _primary(ctx)
    # The net line for both tractions: the caption argues antagonism from it.
    total = {"normal": "sum", "longitudinal": "sum (net)", "lateral": "sum (net)"}.get(force)
    fig, ax, facts = _wheel_figure(ctx, column, ylabel, total=total,
                                   creep=force != "normal")
    if force == "normal":
        extra = _weight_text(ctx, run, traj, ax, facts)
    else:
        extra = _traction_text(ctx, run, traj, column, facts, net=total is not None)
    events, handles, labels, _ = _mark_switches(ctx, run, ax)
    if facts["creep"]:
        handles.append(Line2D([], [], color=CREEP_UNDERLAY, linewidth=5, alpha=0.7))
        labels.append("wheel creeping (‖s‖ < 10 ε)")
    _finish_legend(ax, handles, labels)
    caption = (paper_text + _range_text(facts, run, "N") + extra + events
               + _breaks_text(run, facts))
    return save_figure(fig, ctx.out_dir, stem, title, caption)


def figure_normal_forces(ctx):
    return _wheel_force_figure(ctx, "normal_forces")


def figure_longitudinal_traction(ctx):
    return _wheel_force_figure(ctx, "longitudinal_traction")


def figure_lateral_traction(ctx):
    return _wheel_force_figure(ctx, "lateral_traction")


def _mark_creep_band(run, ax, slips, log):
    """Shades the slips below 10 ε, where a wheel creeps (docs/model.md §7.5:
    a slip proportional to ε, the regularisation standing in for sticking),
    and says so; "" without a finite ε or on a linear axis."""
    level = _creep_level(run)
    if not (log and is_finite(level)):
        return ""
    low, high = ax.get_ylim()
    where = "none of the wheel samples lies there"
    if level > low:
        ax.axhspan(low, min(level, high), color="grey", alpha=0.15,
                   linewidth=0, label="creep (‖s‖ < 10 ε)")
        ax.set_ylim(low, high)
        share = float(np.mean(slips < level)) if slips.size else math.nan
        where = f"shaded; {fmt(100 * share, 2)} % of the wheel samples lie there"
    return (f" Below 10 ε = {fmt(level)} m/s a wheel creeps — its slip is "
            "proportional to ε, the friction regularisation standing in for "
            "sticking, not motion (docs/model.md §7.5): " + where + ".")


def _mark_reversals(ax, reversals):
    """A ▲ at the bottom edge, in the wheel's colour, at each located creep
    reversal: its slip turns through or near zero there. The caption's
    sentence."""
    if not reversals:
        return ""
    trans = blended_transform_factory(ax.transData, ax.transAxes)
    for e in reversals:
        ax.plot([e["t"]], [0.02], marker="^", markersize=7, linestyle="none",
                color=WHEEL_COLOURS.get(e["wheel"], "black"), transform=trans, zorder=5,
                clip_on=False)
    # The legend's entry in grey: each mark has its wheel's colour.
    ax.plot([], [], marker="^", markersize=7, linestyle="none", color="#777777",
            label="located creep reversal (slip turns near 0; wheel's colour)")
    return (" ▲ at the bottom: the located creep reversals, "
            + ", ".join(f"{fmt(e['t'], 5)} s (wheel {e['wheel']})" for e in reversals[:8])
            + ": there the wheel's slip turns through or near zero (its direction "
            "turns by 90° at the located time, within a time ∝ ε); the "
            "depth of its dip on the log axis is that of the output sample nearest "
            "to it (a finer grid dips deeper), not a minimum of the slip. A "
            "wheel's stick window (between its slide→stick and stick→slide "
            "switches, dotted) holds such a turn, marked where it was located.")


def figure_slip(ctx):
    run, traj = _primary(ctx)
    slips = np.concatenate([traj[f"slip{i}"] for i in WHEELS])
    log = bool(np.any(slips > 0))
    fig, ax, facts = _wheel_figure(ctx, "slip{i}", "slip speed ‖s_i‖ [m/s]", log=log,
                                   absolute=True)
    finite = slips[np.isfinite(slips)]
    events, handles, labels, drawn = _mark_switches(ctx, run, ax)
    reversals = _mark_reversals(ax, drawn["creep_reversal"]) if log else ""
    creep = _mark_creep_band(run, ax, finite, log)
    _finish_legend(ax, handles, labels)
    caption = (
        "Fig. 12 — the paper shows that the wheels roll with (near-)zero slip "
        "when friction suffices (μ = 0.5). This run: max slip "
        f"{fmt(_sample_extremes(facts)[1])} m/s over the output samples, median "
        f"{fmt(float(np.median(finite)) if finite.size else math.nan)} m/s"
        + ("" if log else " (all zero: linear axis)")
        + f" ({_run_text(run)})." + creep + reversals + events
        + _breaks_text(run, facts))
    return save_figure(fig, ctx.out_dir, "fig12_slip",
                       "Fig. 12 — slip speeds", caption)


# ------------------------------------------------------------ Figs. 13-14

def trajectory_metrics(traj, run):
    """Traction and slip summaries of one run for the μ-sweep figures; the
    total slip is the run's located one (located_total_slip) where the
    results carry it, else the trapezoid over the output rows; sliding and
    creep are runs.csv's (nan without the columns)."""
    t = traj["t"]
    ok = np.isfinite(t)
    for i in WHEELS:
        ok &= np.isfinite(traj[f"slip{i}"]) & np.isfinite(traj[f"t{i}_lon"])
    t = t[ok]
    slip_sum = sum(np.abs(traj[f"slip{i}"][ok]) for i in WHEELS)
    lon = [float(np.mean(np.abs(traj[f"t{i}_lon"][ok]))) if ok.any() else math.nan
           for i in WHEELS]
    total = sum(np.hypot(traj[f"t{i}_lon"][ok], traj[f"t{i}_lat"][ok])
                for i in WHEELS)
    integral = located_total_slip(run)
    sliding = run.get("sliding_distance", math.nan)
    creep = run.get("creep_distance", math.nan)
    if not is_finite(integral):
        integral = float(np.sum(0.5 * (slip_sum[1:] + slip_sum[:-1]) * np.diff(t))) \
            if t.size > 1 else math.nan
    return {"mean_abs_lon": lon,
            "mean_total_traction": float(np.mean(total)) if ok.any() else math.nan,
            "total_slip": integral,
            "sliding": sliding, "creep": creep}


def located_total_slip(run):
    """The run's own ∫Σ_i ‖s_i‖ dt: runs.csv sliding_distance + creep_distance,
    integrated by the harness with its switches and its 10 ε crossings
    located (docs/model.md §7.5), so independent of the output grid; nan for
    results without the columns."""
    sliding = run.get("sliding_distance", math.nan)
    creep = run.get("creep_distance", math.nan)
    return sliding + creep if is_finite(sliding) and is_finite(creep) else math.nan


def _sweep_data(ctx):
    """(scenes, ok, metrics, failed) of the μ sweep, one entry per scene."""
    rows = sel.mu_sweep_rows(ctx.runs)
    ok = [r for r in rows if is_success(r) and ctx.trajectories.has(r)
          and ctx.trajectories.get(r) is not None]
    if not ok:
        raise MissingData("no successful mu_sweep run with a trajectory for "
                          "figures 13-14")
    metrics = {r["run_id"]: trajectory_metrics(ctx.trajectories.get(r), r)
               for r in ok}
    failed = [r for r in rows if not is_success(r)]
    scenes = sorted({r["scene"] for r in rows},
                    key=lambda s: (s != sel.PAPER_SCENE, s))
    return scenes, ok, metrics, failed


def _scene_mu_min(ctx, scene):
    """(μ_min the scene needs (ref_mu_min), the horizon it is maximised over:
    the t_end of the rows that carry it), from its μ-sweep rows, else from
    any row of the scene; nan when the results do not carry it."""
    for rows in ([r for r in sel.mu_sweep_rows(ctx.runs) if r["scene"] == scene],
                 [r for r in ctx.runs if r["scene"] == scene]):
        value = sel.scene_mu_min(rows)
        if is_finite(value):
            return value, sel.mu_min_horizon(rows, value)
    return math.nan, math.nan


def _method_medians(ok, metrics, key, styles):
    """(method, its style, μ values, median of metrics[key] at each μ) per
    method of the runs ok."""
    for method in sel.method_names(ok):
        mine = sorted((r["mu"], metrics[r["run_id"]][key]) for r in ok
                      if r["method"] == method)
        mus = sorted({m for m, _ in mine})
        vals = [float(np.nanmedian([v for m, v in mine if m == mu])) for mu in mus]
        yield method, styles.get(method) or method_style(method), mus, vals


def _per_method_curve(ax, ok, metrics, key, styles, positive=False, hidden=None):
    """Each method's median of metrics[key] against μ; with positive (a log
    axis) values <= 0 are left out of the drawing (not of the returned
    curves) instead of being dropped silently by the axis. A curve lying on
    an earlier one (figures_methods.coinciding) is drawn dashed over it and
    (method, method it lies on) appended to `hidden`."""
    curves = {}
    for method, style, mus, vals in _method_medians(ok, metrics, key, styles):
        drawn = [v if v > 0 or not positive else math.nan for v in vals]
        kwargs = plot_style(style)
        under = next((m for m, c in curves.items()
                      if coinciding(([x for x, _ in c], [v for _, v in c]), (mus, vals))),
                     None)
        if under is not None:
            kwargs.update(COINCIDING_STYLE)
            if hidden is not None:
                hidden.append((method, under))
        ax.plot(mus, drawn, label=method, **kwargs)
        curves[method] = list(zip(mus, vals))
    return curves


# Height of the strip along the bottom of a μ-sweep panel that holds the
# failed runs' crosses (axes fraction).
FAILURE_STRIP = 0.12


def _mark_failures(ax, failed):
    """A cross per failed run at its μ, in a grey strip along the bottom of
    the axes: the strip keeps them apart from the data, and their height
    carries no value (they would read as a traction or a slip otherwise)."""
    trans = blended_transform_factory(ax.transData, ax.transAxes)
    if failed:
        strip = Rectangle((0, 0), 1, FAILURE_STRIP, transform=ax.transAxes,
                          facecolor="#eeeeee", edgecolor="none", zorder=0)
        strip.failure_strip = True
        ax.add_patch(strip)
    labelled = set()
    for k, r in enumerate(sorted(failed, key=lambda r: (r["mu"], r["method"]))):
        colour = method_style(r["method"])[0]
        ax.plot([r["mu"]], [0.03 + 0.03 * (k % 3)], marker="x", color=colour,
                markersize=9, markeredgewidth=2, transform=trans, linestyle="none")
        cls, detail = sel.failure_cause(r)
        text = r["status"] if cls == sel.UNKNOWN else f"{cls}: {detail}"
        if (r["mu"], text) not in labelled:
            labelled.add((r["mu"], text))
            ax.text(r["mu"], 0.14, " " + text, rotation=90, fontsize=6.5,
                    ha="center", va="bottom", transform=trans, color="#333333")


def _room_for_failures(axes, strip=FAILURE_STRIP):
    """Lowers the y-limit of the axes that carry a failure strip
    (_mark_failures) until their data lie above the strip (shared axes move
    together): the crosses never sit on a curve."""
    for ax in axes:
        if not any(getattr(p, "failure_strip", False) for p in ax.patches):
            continue
        lo, hi = ax.get_ylim()
        log = ax.get_yscale() == "log"
        a, b = (math.log10(lo), math.log10(hi)) if log else (lo, hi)
        a -= (strip + 0.03) * (b - a) / (1 - strip - 0.03)
        ax.set_ylim(10 ** a if log else a, hi)


def _mu_min_line(ax, mu_min, horizon=math.nan):
    """The dotted μ_min(ref) line, labelled with its horizon inside the axes
    beside the line (never over the panel title)."""
    if is_finite(mu_min):
        ax.axvline(mu_min, color="grey", linestyle=":", linewidth=1.6)
        return vline_label(ax, mu_min, f"μ_min(ref) = {fmt(mu_min)}"
                           + horizon_text(horizon, " (0–{} s)"))
    return None


def _stop_lag_text(rows):
    """', stops <a>–<b> s after the reference's' from the rows' err_stop_t
    (runs.csv: t_reached − t_ref of a physical stop); '' without any."""
    lags = [r.get("err_stop_t") for r in rows]
    lags = [v for v in lags if is_finite(v)]
    if not lags:
        return ""
    return f", stop − reference's stop {span_text(lags)} s"


def _failed_text(failed):
    if not failed:
        return "no μ failed"
    parts = {}
    for r in failed:
        cls, detail = sel.failure_cause(r)
        what = r["status"] if cls == sel.UNKNOWN else f"{cls} {detail}"
        parts.setdefault((r["scene"], r["mu"], what), []).append(r)
    return "failed: " + "; ".join(
        f"{scene} μ={fmt(mu)} {what} ({len(rows)} methods{_stop_lag_text(rows)})"
        for (scene, mu, what), rows in sorted(parts.items()))


def _mu_min_needs(panels):
    """'<scene> needs μ ≥ <μ_min> over 0–<t_end> s' of each panel with a
    μ_min, '; '-joined."""
    return "; ".join(f"{p['scene']} needs μ ≥ {fmt(p['mu_min'])}"
                     f"{horizon_text(p.get('mu_min_horizon', math.nan))}" for p in panels
                     if is_finite(p["mu_min"]))


def _scene_title(ctx, scene, rows):
    """The parameters held fixed over a μ-sweep panel's runs (all of the
    scene's rows, failed ones included); μ is swept, so never in it."""
    return fixed_label([r for r in rows if r["scene"] == scene], ctx.references,
                       omit=("mu",)) or scene


def _sweep_legend(fig, gs_cell, ok, failed, styles, more=()):
    extra = [Line2D([], [], color="grey", linestyle=":", label="μ_min(ref): friction\nthe scene needs")]
    extra.extend(more)
    if failed:
        extra.append(Line2D([], [], marker="x", color="#444444", markeredgewidth=2,
                            linestyle="none", label="failed at this μ\n(grey strip: its height\ncarries no value)"))
    ax = fig.add_subplot(gs_cell)
    ax.axis("off")
    ax.legend(handles=style_legend_handles(ok, extra, styles), loc="upper left",
              frameon=False)


def _slip_regimes(ok, mu):
    """{scene: (median sliding_distance, median creep_distance, eps)} of the
    successful runs at μ = mu; {} for results without the columns."""
    out = {}
    for scene in sorted({r["scene"] for r in ok}):
        rows = [r for r in ok if r["scene"] == scene and r["mu"] == mu
                and is_finite(r.get("sliding_distance", math.nan))]
        if rows:
            out[scene] = (float(np.median([r["sliding_distance"] for r in rows])),
                          float(np.median([r["creep_distance"] for r in rows])),
                          rows[0].get("eps", math.nan))
    return out


def slip_regime_text(scene, total, regime):
    """How a scene's slip reads: sliding with its creep, or 'no sliding;
    creep X m, proportional to ε' (never a ratio against sliding)."""
    if regime is None:
        return f"{scene} total slip {fmt(total)} m"
    sliding, creep, eps = regime
    if sliding <= 0:
        return (f"{scene} no sliding; creep {fmt(creep)} m, proportional to "
                f"ε = {fmt(eps)} m/s (the regularisation, not physics)")
    return f"{scene} slides {fmt(sliding)} m (plus creep {fmt(creep)} m)"


def _common_mu_ratio(ctx, scenes, ok, metrics, key):
    """(μ, {scene: median value}) at the μ closest to 0.5 where every scene
    has a successful run; (nan, {}) if none."""
    per_scene = {s: {} for s in scenes}
    for r in ok:
        per_scene[r["scene"]].setdefault(r["mu"], []).append(metrics[r["run_id"]][key])
    common = set.intersection(*(set(v) for v in per_scene.values())) if per_scene else set()
    if not common:
        return math.nan, {}
    mu = min(common, key=lambda m: (abs(m - sel.PAPER_MU), m))
    return mu, {s: float(np.nanmedian(per_scene[s][mu])) for s in scenes}


def figure_traction_vs_mu(ctx):
    scenes, ok, metrics, failed = _sweep_data(ctx)
    n = len(scenes)
    fig = new_figure(4.4 * n + 2.6, 7.6)
    gs = fig.add_gridspec(2, n + 1, width_ratios=[1] * n + [0.6])
    panels = []
    share_total = share_wheel = None
    for k, scene in enumerate(scenes):
        mine_ok = [r for r in ok if r["scene"] == scene]
        mine_failed = [r for r in failed if r["scene"] == scene]
        ax_total = fig.add_subplot(gs[0, k], sharey=share_total)
        ax_wheel = fig.add_subplot(gs[1, k], sharey=share_wheel, sharex=ax_total)
        share_total, share_wheel = share_total or ax_total, share_wheel or ax_wheel
        hidden = []
        curves = _per_method_curve(ax_total, mine_ok, metrics, "mean_total_traction",
                                   ctx.styles, hidden=hidden)
        _mark_failures(ax_total, mine_failed)
        mu_min, horizon = _scene_mu_min(ctx, scene)
        _mu_min_line(ax_total, mu_min, horizon)
        title = _scene_title(ctx, scene, mine_ok + mine_failed)
        ax_total.set_title(f"{title}\ntotal traction per method", fontsize=9)
        ax_total.set_xlabel("friction coefficient μ [-]")
        ax_total.set_ylabel("mean Σ_i ‖traction_i‖ [N]")
        if not mine_ok:
            no_data(ax_total, "no successful run")
            no_data(ax_wheel, "no successful run")
            panels.append({"scene": scene, "methods": [], "mu_min": mu_min,
                           "mu_min_horizon": horizon, "title": title})
            continue
        main = _main_method(ctx, mine_ok)
        runs = sorted((r for r in mine_ok if r["method"] == main), key=lambda r: r["mu"])
        for i, (colour, style) in zip(WHEELS, WHEEL_STYLES):
            ax_wheel.plot([r["mu"] for r in runs],
                          [metrics[r["run_id"]]["mean_abs_lon"][i - 1] for r in runs],
                          color=colour, linestyle=style, marker="o", label=f"wheel {i}")
        _mu_min_line(ax_wheel, mu_min, horizon)
        ax_wheel.set_xlabel("friction coefficient μ [-]")
        ax_wheel.set_ylabel("mean |longitudinal traction| [N]")
        ax_wheel.set_title(f"{scene}: per wheel, {main}", fontsize=9)
        ax_wheel.legend(loc="best", fontsize=7)
        panels.append({"scene": scene, "methods": sorted(curves), "mu_min": mu_min,
                       "mu_min_horizon": horizon, "main": main,
                       "curves": {m: c for m, c in curves.items()}, "title": title,
                       "hidden": hidden})
    _room_for_failures(fig.axes)
    _sweep_legend(fig, gs[:, n], ok, failed, ctx.styles)
    mu, values = _common_mu_ratio(ctx, scenes, ok, metrics, "mean_total_traction")
    compare = (", ".join(f"{s} {fmt(v)} N" for s, v in values.items()) + f" at μ={fmt(mu)}"
               if values else "no μ where every scene succeeded")
    record = save_figure(fig, ctx.out_dir, "fig13_traction_vs_mu",
                         "Fig. 13 — traction vs μ",
                         _traction_vs_mu_caption(panels, compare, failed))
    record.data = {"panels": panels}
    return record


def _traction_vs_mu_caption(panels, compare, failed):
    growth = "; ".join(
        f"{p['scene']} ({p['main']}) {fmt(curve[0][1])} N at μ={fmt(curve[0][0])} to "
        f"{fmt(curve[-1][1])} N at μ={fmt(curve[-1][0])}"
        for p in panels if p.get("main") for curve in [p["curves"].get(p["main"], [])]
        if curve)
    needs = _mu_min_needs(panels)
    return (
        "Fig. 13 — the paper shows how the traction the wheels develop varies "
        "with μ, for the paper's fixed-camber mode and for the passive variable "
        "camber (pvc). One column per scene/mode (never averaged over them), its "
        "two rows on one μ axis. Top row: per method (median over runs at a μ) "
        "the run's mean of the total traction norm Σ_i ‖(t_lon, t_lat)_i‖; bottom "
        "row: per wheel, for one method, the mean |longitudinal traction| only "
        "(not the norm). In paper mode the robot is over-actuated: the per-wheel "
        "tractions include internal (antagonistic) forces that scale with μ and, "
        "for creeping wheels, are fixed by the creep regularisation (statically "
        "indeterminate, docs/model.md §7.5), so their growth with μ is not "
        "traction the terrain demands (Fig. 10 shows the wheels pulling against "
        "each other); pvc mode is statically determinate. This run: mean total "
        f"traction {growth + '; ' if growth else ''}{compare}"
        + (f"; {needs} (μ_min(ref): the solver's μ_min maximised over the "
           "reference trajectory of that horizon; over a shorter one, as the "
           "stability charts' runs, it can be smaller)" if needs else
           "; μ_min not drawn (these results carry no ref_mu_min column)")
        + _hidden_text(panels)
        + f"; {_failed_text(failed)}.")


def _hidden_text(panels):
    """The caption's note on curves drawn dashed over an equal one."""
    pairs = [f"{p['scene']}: {a} on {b}" for p in panels for a, b in p.get("hidden", [])]
    if not pairs:
        return ""
    return ("; curves within 5 % of an earlier one at 95 % of their points, drawn "
            "dashed over it: " + ", ".join(pairs))


def _main_method(ctx, ok):
    names = sel.method_names(ok)
    if ctx.primary is not None and ctx.primary["method"] in names:
        return ctx.primary["method"]
    return names[0]


CREEP_COLOUR = "#9a9a9a"


def _split_slip(ok, metrics):
    """True when every run carries its located sliding and creep distances
    (runs.csv sliding_distance, creep_distance): Fig. 14 then draws them
    apart; else the total (the trapezoid over the output rows) as before."""
    return bool(ok) and all(is_finite(metrics[r["run_id"]]["sliding"])
                            and is_finite(metrics[r["run_id"]]["creep"]) for r in ok)


def _creep_curves(ax, ok, metrics, styles):
    """Each method's creep distance against μ, grey and thin: the friction
    regularisation (proportional to ε), drawn beside the sliding, never in
    a method's colour."""
    curves = {}
    for method, style, mus, vals in _method_medians(ok, metrics, "creep", styles):
        ax.plot(mus, vals, color=CREEP_COLOUR, marker=style.marker,
                markerfacecolor="none", linestyle=style.linestyle, linewidth=0.9,
                markersize=4, zorder=1)
        curves[method] = list(zip(mus, vals))
    return curves


def _slip_panel(ax, mine_ok, metrics, styles, split, log):
    """One scene's curves: (sliding or total curves, creep curves or {},
    whether the scene slides at all)."""
    key = "sliding" if split else "total_slip"
    curves = _per_method_curve(ax, mine_ok, metrics, key, styles, positive=log)
    if not split:
        return curves, {}, True
    creep = _creep_curves(ax, mine_ok, metrics, styles)
    slides = any(v > 0 for c in curves.values() for _, v in c)
    if mine_ok and not slides:
        ax.text(0.5, 0.5, "no sliding at any μ that ran\n(sliding_distance = 0):\n"
                "grey is creep only, ∝ ε", transform=ax.transAxes, ha="center",
                va="center", fontsize=8, color="#333333",
                bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.85})
    return curves, creep, slides


def figure_total_slip_vs_mu(ctx):
    scenes, ok, metrics, failed = _sweep_data(ctx)
    n = len(scenes)
    fig = new_figure(4.4 * n + 2.6, 4.6)
    gs = fig.add_gridspec(1, n + 1, width_ratios=[1] * n + [0.6])
    split = _split_slip(ok, metrics)
    values = [metrics[r["run_id"]][k] for r in ok
              for k in (("sliding", "creep") if split else ("total_slip",))]
    log = spans_decades(values, 1.0)
    panels, share = [], None
    for k, scene in enumerate(scenes):
        ax = fig.add_subplot(gs[0, k], sharey=share)
        share = share or ax
        mine_ok = [r for r in ok if r["scene"] == scene]
        curves, creep, slides = _slip_panel(ax, mine_ok, metrics, ctx.styles,
                                            split, log)
        _mark_failures(ax, [r for r in failed if r["scene"] == scene])
        mu_min, horizon = _scene_mu_min(ctx, scene)
        _mu_min_line(ax, mu_min, horizon)
        if log:
            ax.set_yscale("log")
        ax.set_xlabel("friction coefficient μ [-]")
        ax.set_ylabel("slip distance ∫Σ_i ‖s_i‖ dt [m]" if split else
                      "total slip ∫Σ_i ‖s_i‖ dt [m]")
        title = _scene_title(ctx, scene, mine_ok + failed)
        ax.set_title(title, fontsize=9)
        if not mine_ok:
            no_data(ax, "no successful run")
        panels.append({"scene": scene, "methods": sorted(curves), "mu_min": mu_min,
                       "mu_min_horizon": horizon,
                       "curves": curves, "creep_curves": creep, "slides": slides,
                       "title": title})
    extra = ([Line2D([], [], color=CREEP_COLOUR, marker="o", markerfacecolor="none",
                     linewidth=0.9, label="creep: friction\nregularisation (∝ ε),\nnot physics")]
             if split else [])
    _room_for_failures(fig.axes)
    _sweep_legend(fig, gs[0, n], ok, failed, ctx.styles, extra)
    mu, per_scene = _common_mu_ratio(ctx, scenes, ok, metrics, "total_slip")
    regimes = _slip_regimes(ok, mu)
    headline = ""
    if per_scene:
        headline = f" At μ={fmt(mu)}: " + "; ".join(
            slip_regime_text(s, v, regimes.get(s)) for s, v in per_scene.items()) + "."
    sliding = {s: reg[0] for s, reg in regimes.items() if reg[0] > 0}
    if len(sliding) >= 2:
        ordered = sorted(sliding.items(), key=lambda kv: kv[1])
        (low_s, low_v), (high_s, high_v) = ordered[0], ordered[-1]
        headline += f" {low_s} slides {fmt(high_v / low_v, 2)}× less than {high_s}."
    needs = _mu_min_needs(panels)
    what = (
        "The slip holds two regimes (docs/model.md §7.5), drawn apart: sliding "
        "on the friction cone (method colours: the physics) and creep below it "
        "(grey, thin: the friction regularisation, proportional to ε, not "
        "physics); a scene whose successful runs never slide shows "
        "creep only in its panel and "
        "is not compared with paper mode's sliding. Each point is the run's own "
        "integral (runs.csv sliding_distance and creep_distance, its switches "
        "located, independent of the output grid)." if split else
        "The total slip holds two regimes (docs/model.md §7.5): sliding on the "
        "friction cone, and creep below it, which is the friction "
        "regularisation (proportional to ε), not physics; these results carry "
        "no sliding_distance / creep_distance columns, so each point is the "
        "trapezoid over the output rows (it depends on the output grid) and the "
        "two regimes are not drawn apart.")
    caption = (
        "Fig. 14 — the paper shows the accumulated slip falling as μ grows and "
        "the passive variable camber slipping far less than the fixed camber, "
        "at the price of needing more friction. One panel per scene/mode on a "
        "shared axis (never averaged over them), one curve per method. " + what
        + headline
        + (f" {needs} (μ_min(ref), dotted)." if needs else
           " μ_min not drawn (these results carry no ref_mu_min column).")
        + f" {_failed_text(failed)}.")
    record = save_figure(fig, ctx.out_dir, "fig14_total_slip_vs_mu",
                         "Fig. 14 — total slip vs μ", caption)
    record.data = {"panels": panels, "compare_mu": mu, "per_scene": per_scene,
                   "regimes": regimes, "split": split}
    return record
