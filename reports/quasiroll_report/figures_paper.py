"""The paper's figures (Figs. 5-15) reproduced from one run of the paper scene
at μ = 0.5, the μ sweep, and a Baumgarte/projection pair."""

import math

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from matplotlib.transforms import blended_transform_factory

from . import selection as sel
from .data import dae_option, has_dae_option, is_finite, is_success
from .plotting import (COMPONENT_STYLES, MissingData, WHEEL_STYLES, fmt, span_text,
                       new_figure, no_data, positive, save_figure,
                       spans_decades, vline_label)
from .figures_methods import style_legend_handles
from . import robot
from .problems import (fixed_label, method_style, plot_style, robot_geometry,
                       scene_mode)
from .terrain import describe_terrain, terrain_height

WHEELS = (1, 2, 3)


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
            delta = math.degrees(float(row[f"delta{i}"]))
            text = f"δ{i}={delta:+.1f}°"
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
    ax.set_title(f"{run['scene']} ({mode} mode)\n{run['method']}, Δt={fmt(run['dt'])} s",
                 fontsize=10)
    return {"run": run, "times": [float(traj["t"][k]) for k in indices],
            "camber_labels": camber_labels,
            "max_camber_deg": float(np.degrees(np.max(np.abs(cambers)))) if cambers.size
            else math.nan, "spec": spec}


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
    if pvc is None:
        parts.append("no successful pvc-mode run at μ = 0.5 with a trajectory, so "
                     "only paper mode is shown")
        same = f"Method: {paper['method']}."
    elif pvc["method"] == paper["method"]:
        same = (f"Both panels from the same method, {paper['method']} (the method "
                "both scenes ran at μ = 0.5), so they differ only by the camber mode.")
    else:
        same = ("The two scenes share no successful method at μ = 0.5, so the "
                f"panels are from different methods: {paper['method']} (paper), "
                f"{pvc['method']} (pvc).")
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
                               "camber_labels": p["camber_labels"]} for p in panels]}
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
    for i, (colour, style) in zip(WHEELS, WHEEL_STYLES):
        ax.plot(traj[f"c{i}_x"], traj[f"c{i}_y"], color=colour, linestyle=style,
                label=f"contact point wheel {i}")
    ax.plot(traj["x"], traj["y"], color="black", linewidth=1.8,
            label="platform centre")
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


def _wheel_figure(ctx, column, ylabel, paper_text, total=False, log=False,
                  absolute=False):
    """One line per wheel of column.format(i=i) against t, plus the caption."""
    run, traj = _primary(ctx)
    fig = new_figure(8, 4.2)
    ax = fig.add_subplot()
    for i, (colour, style) in zip(WHEELS, WHEEL_STYLES):
        values = traj[column.format(i=i)]
        values = np.abs(values) if absolute else values
        ax.plot(traj["t"], positive(values) if log else values, color=colour,
                linestyle=style, label=f"wheel {i}")
    if total:
        summed = sum(traj[column.format(i=i)] for i in WHEELS)
        ax.plot(traj["t"], positive(summed) if log else summed, color="black",
                linewidth=1.0, linestyle=":", label="sum")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    ax.legend(loc="best")
    low, high = _extremes(traj, [column.format(i=i) for i in WHEELS])
    caption = (f"{paper_text} This run: range [{fmt(low)}, {fmt(high)}] over "
               f"the three wheels ({_run_text(run)}).")
    return fig, caption


# The per-wheel force figures: (file stem, title, column, y label, what the
# paper shows, with the sum over the wheels).
_WHEEL_FORCE_FIGURES = {
    "normal_forces": (
        "fig09_normal_forces", "Fig. 9 — normal forces", "n{i}",
        "normal force N_i [N]",
        "Fig. 9 — the paper shows the three normal forces redistributing as "
        "the wheels cross the bumps, their sum balancing the weight.", True),
    "longitudinal_traction": (
        "fig10_longitudinal_traction", "Fig. 10 — longitudinal traction",
        "t{i}_lon", "longitudinal traction [N]",
        "Fig. 10 — the paper shows the longitudinal traction each wheel must "
        "provide to climb and descend the bumps.", False),
    "lateral_traction": (
        "fig11_lateral_traction", "Fig. 11 — lateral traction", "t{i}_lat",
        "lateral traction [N]",
        "Fig. 11 — the paper shows the lateral traction that keeps the wheels "
        "from side-slipping on the sloped terrain.", False),
}


# Vertical event lines of the force figures: kind -> (legend label, style).
_EVENT_LINES = {"switch": ("stick/slide switch", (0, (1, 2))),
                "creep_reversal": ("creep reversal", (0, (6, 2, 1, 2))),
                "solution_jump": ("solution jump", (0, (4, 2)))}


def _jump_lines(jumps):
    """One line per solution jump time: a jump is the whole solution's (one
    entry per wheel, one bracket), drawn black, not overdrawn in the wheels'
    colours."""
    return [{"t": t, "wheel": None} for t in sorted({e["t"] for e in jumps})]


def _jump_sentence(jump_lines):
    if not jump_lines:
        return ""
    return (f" Dashed black: {len(jump_lines)} solution jump(s), where the "
            "root the run followed ends in a fold and the slips of all wheels "
            "jump to another root (docs/model.md §8.6; in the limit ε → 0 a "
            "wheel starts to slide there): "
            + ", ".join(f"{fmt(e['t'])} s" for e in jump_lines[:8]) + ".")


def _mark_jumps(ctx, run, ax):
    """The run's solution jumps as black dashed verticals (labelled for the
    legend); the caption's sentence, "" when there are none or no
    switches/ file."""
    events = ctx.trajectories.switches(run)
    lines = _jump_lines([e for e in events or ()
                         if e["kind"] == "solution_jump"])
    label, style = _EVENT_LINES["solution_jump"]
    for k, e in enumerate(lines):
        ax.axvline(e["t"], color="black", linestyle=style, linewidth=0.9,
                   alpha=0.8, label=label if k == 0 else None)
    if lines:
        ax.legend(loc="best")
    return _jump_sentence(lines)


def _mark_switches(ctx, run, ax):
    """Vertical lines at the run's located stick/slide switches and creep
    reversals, in the wheel's colour; the caption's sentences about them."""
    events = ctx.trajectories.switches(run)
    if events is None:
        return (" The run's switch times are not in the results "
                "(no switches/ file), so none are marked.")
    switches = [e for e in events if e["kind"] == "switch"]
    reversals = [e for e in events if e["kind"] == "creep_reversal"]
    jumps = [e for e in events if e["kind"] == "solution_jump"]
    colours = dict(zip(WHEELS, (c for c, _ in WHEEL_STYLES)))
    handles, labels = ax.get_legend_handles_labels()
    jump_lines = _jump_lines(jumps)
    for kind, drawn in (("switch", switches), ("creep_reversal", reversals),
                        ("solution_jump", jump_lines)):
        label, style = _EVENT_LINES[kind]
        for e in drawn:
            ax.axvline(e["t"], color=colours.get(e["wheel"], "black"),
                       linestyle=style, linewidth=0.9, alpha=0.8)
        if drawn:
            handles.append(Line2D(
                [], [], linestyle=style,
                color="black" if kind == "solution_jump" else "grey"))
            labels.append(label)
    if events:
        ax.legend(handles, labels, loc="best")
    turns = ""
    if reversals:
        turns = (f" Dash-dotted: the {len(reversals)} creep reversal(s), a "
                 "creeping wheel's slip reversing, where the tractions turn "
                 "within a time proportional to ε (docs/model.md §8.6): "
                 + ", ".join(f"{fmt(e['t'])} s (wheel {e['wheel']})"
                             for e in reversals[:8]) + ".")
    turns += _jump_sentence(jump_lines)
    if not switches:
        return (" No wheel changed between sticking and sliding in this run "
                "(switch location on)." + turns
                if run.get("locate_switches") != "false"
                else " Switch location was off for this run.")
    located = sum(1 for e in switches if e["located"])
    listed = ", ".join(
        f"{fmt(e['t'])} s (wheel {e['wheel']} {e['from']}→{e['to']})"
        for e in switches[:8])
    more = f" and {len(switches) - 8} more" if len(switches) > 8 else ""
    return (f" Dotted verticals, in the wheel's colour: the {len(switches)} "
            f"stick/slide switches of this run ({located} located to the "
            f"switch tolerance where a wheel's friction margin crosses 5e-5, "
            f"docs/model.md §8.6; a wheel that reaches its cone slowly starts "
            f"to slide later than that, at a solution jump where there is "
            f"one): {listed}{more}." + turns)


def _wheel_force_figure(ctx, name):
    stem, title, column, ylabel, paper_text, total = _WHEEL_FORCE_FIGURES[name]
    fig, caption = _wheel_figure(ctx, column, ylabel, paper_text, total=total)
    run, _ = _primary(ctx)
    caption += _mark_switches(ctx, run, fig.axes[0])
    caption += (f" Lines join the output samples (Δt = {fmt(run['dt'])} s): a "
                "change faster than that — at a switch, or the tractions' "
                "turns between switches, whose width is proportional to ε "
                "(docs/model.md §8.6) — shows as a slope between two samples.")
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
    eps = run.get("eps", math.nan)
    if not (log and is_finite(eps) and eps > 0):
        return ""
    level = 10 * eps
    low, high = ax.get_ylim()
    where = "none of the wheel samples lies there"
    if level > low:
        ax.axhspan(low, min(level, high), color="grey", alpha=0.15,
                   linewidth=0, label="creep (‖s‖ < 10 ε)")
        ax.set_ylim(low, high)
        ax.legend(loc="best")
        share = float(np.mean(slips < level)) if slips.size else math.nan
        where = f"shaded; {fmt(100 * share, 2)} % of the wheel samples lie there"
    return (f" Below 10 ε = {fmt(level)} m/s a wheel creeps — its slip is "
            "proportional to ε, the friction regularisation standing in for "
            "sticking, not motion (docs/model.md §7.5): " + where + ".")


def figure_slip(ctx):
    run, traj = _primary(ctx)
    slips = np.concatenate([traj[f"slip{i}"] for i in WHEELS])
    log = bool(np.any(slips > 0))
    fig, _ = _wheel_figure(
        ctx, "slip{i}", "slip speed ‖s_i‖ [m/s]", "", log=log,
        absolute=True)
    finite = slips[np.isfinite(slips)]
    jumps = _mark_jumps(ctx, run, fig.axes[0])
    caption = (
        "Fig. 12 — the paper shows that the wheels roll with (near-)zero slip "
        "when friction suffices (μ = 0.5). This run: max slip "
        f"{fmt(float(finite.max()) if finite.size else math.nan)} m/s, median "
        f"{fmt(float(np.median(finite)) if finite.size else math.nan)} m/s"
        + ("" if log else " (all zero: linear axis)")
        + f" ({_run_text(run)})." + _mark_creep_band(run, fig.axes[0], finite, log)
        + jumps + (" The lines join the output samples: a jump shows as a "
                   "slope over the interval that holds it." if jumps else ""))
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
    """μ_min the scene needs (ref_mu_min), from its μ-sweep rows, else from
    any row of the scene; nan when the results do not carry it."""
    value = sel.scene_mu_min([r for r in sel.mu_sweep_rows(ctx.runs) if r["scene"] == scene])
    if not is_finite(value):
        value = sel.scene_mu_min([r for r in ctx.runs if r["scene"] == scene])
    return value


def _method_medians(ok, metrics, key, styles):
    """(method, its style, μ values, median of metrics[key] at each μ) per
    method of the runs ok."""
    for method in sel.method_names(ok):
        mine = sorted((r["mu"], metrics[r["run_id"]][key]) for r in ok
                      if r["method"] == method)
        mus = sorted({m for m, _ in mine})
        vals = [float(np.nanmedian([v for m, v in mine if m == mu])) for mu in mus]
        yield method, styles.get(method) or method_style(method), mus, vals


def _per_method_curve(ax, ok, metrics, key, styles, positive=False):
    """Each method's median of metrics[key] against μ; with positive (a log
    axis) values <= 0 are left out of the drawing (not of the returned
    curves) instead of being dropped silently by the axis."""
    curves = {}
    for method, style, mus, vals in _method_medians(ok, metrics, key, styles):
        drawn = [v if v > 0 or not positive else math.nan for v in vals]
        ax.plot(mus, drawn, label=method, **plot_style(style))
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


def _mu_min_line(ax, mu_min):
    """The dotted μ_min(ref) line, labelled inside the axes beside the line
    (never over the panel title)."""
    if is_finite(mu_min):
        ax.axvline(mu_min, color="grey", linestyle=":", linewidth=1.6)
        return vline_label(ax, mu_min, f"μ_min(ref) = {fmt(mu_min)}")
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
    """'<scene> needs μ ≥ <μ_min>' of each panel with a μ_min, '; '-joined."""
    return "; ".join(f"{p['scene']} needs μ ≥ {fmt(p['mu_min'])}" for p in panels
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
        ax_wheel = fig.add_subplot(gs[1, k], sharey=share_wheel)
        share_total, share_wheel = share_total or ax_total, share_wheel or ax_wheel
        curves = _per_method_curve(ax_total, mine_ok, metrics, "mean_total_traction",
                                   ctx.styles)
        _mark_failures(ax_total, mine_failed)
        mu_min = _scene_mu_min(ctx, scene)
        _mu_min_line(ax_total, mu_min)
        title = _scene_title(ctx, scene, mine_ok + mine_failed)
        ax_total.set_title(f"{title}\ntotal traction per method", fontsize=9)
        ax_total.set_xlabel("friction coefficient μ [-]")
        ax_total.set_ylabel("mean Σ_i ‖traction_i‖ [N]")
        if not mine_ok:
            no_data(ax_total, "no successful run")
            no_data(ax_wheel, "no successful run")
            panels.append({"scene": scene, "methods": [], "mu_min": mu_min,
                           "title": title})
            continue
        main = _main_method(ctx, mine_ok)
        runs = sorted((r for r in mine_ok if r["method"] == main), key=lambda r: r["mu"])
        for i, (colour, style) in zip(WHEELS, WHEEL_STYLES):
            ax_wheel.plot([r["mu"] for r in runs],
                          [metrics[r["run_id"]]["mean_abs_lon"][i - 1] for r in runs],
                          color=colour, linestyle=style, marker="o", label=f"wheel {i}")
        _mu_min_line(ax_wheel, mu_min)
        ax_wheel.set_xlabel("friction coefficient μ [-]")
        ax_wheel.set_ylabel("mean |longitudinal traction| [N]")
        ax_wheel.set_title(f"{scene}: per wheel, {main}", fontsize=9)
        ax_wheel.legend(loc="best", fontsize=7)
        panels.append({"scene": scene, "methods": sorted(curves), "mu_min": mu_min,
                       "curves": {m: c for m, c in curves.items()}, "title": title})
    _room_for_failures(fig.axes)
    _sweep_legend(fig, gs[:, n], ok, failed, ctx.styles)
    mu, values = _common_mu_ratio(ctx, scenes, ok, metrics, "mean_total_traction")
    compare = (", ".join(f"{s} {fmt(v)} N" for s, v in values.items()) + f" at μ={fmt(mu)}"
               if values else "no μ where every scene succeeded")
    needs = _mu_min_needs(panels)
    caption = (
        "Fig. 13 — the paper shows how the traction the wheels develop varies "
        "with μ, for the paper's fixed-camber mode and for the passive variable "
        "camber (pvc). One column per scene/mode (never averaged over them), one "
        "curve per method (median over runs at a μ); bottom row per wheel for one "
        f"method. This run: mean total traction {compare}"
        + (f"; {needs} (μ_min(ref): the solver's μ_min maximised over the "
           "reference trajectory)" if needs else
           "; μ_min not drawn (these results carry no ref_mu_min column)")
        + f"; {_failed_text(failed)}.")
    record = save_figure(fig, ctx.out_dir, "fig13_traction_vs_mu",
                         "Fig. 13 — traction vs μ", caption)
    record.data = {"panels": panels}
    return record


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
        ax.text(0.5, 0.62, "no sliding at any μ\n(sliding_distance = 0):\n"
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
        mu_min = _scene_mu_min(ctx, scene)
        _mu_min_line(ax, mu_min)
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
        "physics); a pvc robot never slides, so its panel shows creep only and "
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


# ---------------------------------------------------------------- Fig. 15

def _sigma(run):
    """The run's Baumgarte gain σ, or None for an integrator without one (its
    option table has no baumgarte_sigma: the runs.csv sigma column is only
    the unused shorthand there)."""
    if not has_dae_option(run, "baumgarte_sigma"):
        return None
    value = dae_option(run, "baumgarte_sigma", run["sigma"])
    try:
        value = float(value)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def figure_stabilisation(ctx):
    pair = sel.stabilisation_pair(ctx.runs, ctx.trajectories.has, ctx.primary)
    pair = [r for r in pair if r is not None]
    if not pair:
        raise MissingData("no successful rk-baumgarte or rk-projection run with "
                          "a trajectory for figure 15")
    fig = new_figure(8, 4.2)
    ax = fig.add_subplot()
    parts = []
    for run in pair:
        traj = ctx.trajectories.get(run)
        ax.plot(traj["t"], positive(traj["drift"]), **plot_style(ctx.styles[run["method"]]),
                markevery=0.1, label=f"{run['dae']} ({run['method']}, "
                f"Δt={fmt(run['dt'])} s"
                + (f", σ={fmt(_sigma(run))} 1/s)" if _sigma(run) is not None else ")"))
        finite = traj["drift"][np.isfinite(traj["drift"])]
        parts.append(f"{run['dae']} max {fmt(float(finite.max()) if finite.size else math.nan)}"
                     f", final {fmt(float(finite[-1]) if finite.size else math.nan)}")
    if not any(np.any(positive(ctx.trajectories.get(r)["drift"]) > 0) for r in pair):
        no_data(ax, "drift is zero everywhere")
    else:
        ax.set_yscale("log")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("‖H(Θ)‖∞ [m, rad]")
    ax.legend(loc="best")
    missing = "" if len(pair) == 2 else " (only one of the pair is available)"
    caption = (
        "Fig. 15 — the paper shows that Baumgarte stabilisation keeps the "
        "holonomic loop-closure violation bounded. This run: "
        + "; ".join(parts) + missing + ".")
    record = save_figure(fig, ctx.out_dir, "fig15_stabilisation",
                         "Fig. 15 — constraint stabilisation", caption)
    record.data = {"legend": [t.get_text() for t in ax.get_legend().get_texts()]}
    return record
