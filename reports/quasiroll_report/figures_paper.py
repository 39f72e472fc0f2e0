"""The paper's figures (Figs. 5-15) reproduced from one run of the paper scene
at μ = 0.5, the μ sweep, and a Baumgarte/projection pair."""

import math

import numpy as np
from matplotlib import cm
from matplotlib.transforms import blended_transform_factory

from . import selection as sel
from .data import is_finite, is_success
from .plotting import (COMPONENT_STYLES, MissingData, WHEEL_STYLES, fmt,
                       new_figure, no_data, positive, save_figure,
                       spans_decades)
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


def _draw_snapshots(ax, traj, indices):
    colours = cm.viridis(np.linspace(0.0, 0.9, max(len(indices), 1)))
    for colour, k in zip(colours, indices):
        px = [traj[f"c{i}_x"][k] for i in WHEELS + (1,)]
        py = [traj[f"c{i}_y"][k] for i in WHEELS + (1,)]
        pz = [traj[f"c{i}_z"][k] for i in WHEELS + (1,)]
        ax.plot(px, py, pz, color=colour, linewidth=2.0, zorder=10,
                label=f"platform t={traj['t'][k]:.3g} s")
        for i, (wc, _) in zip(WHEELS, WHEEL_STYLES):
            ax.scatter([traj[f"c{i}_x"][k]], [traj[f"c{i}_y"][k]],
                       [traj[f"c{i}_z"][k]], color=wc, s=22, depthshade=False,
                       zorder=11)


def figure_snapshots(ctx):
    run, traj = _primary(ctx)
    spec = ctx.terrain(run["scene"])
    fig = new_figure(9, 7)
    ax = fig.add_subplot(projection="3d")
    box = _terrain_box(traj)
    finite = _finite_rows(traj)
    zs = np.concatenate([traj[f"c{i}_z"][finite] for i in WHEELS] + [traj["z"]])
    if spec is not None:
        gx, gy, gz = _terrain_grid(spec, box, 70)
        ax.plot_surface(gx, gy, gz, cmap="gist_earth", alpha=0.55, linewidth=0,
                        antialiased=True, rstride=2, cstride=2)
        zs = np.concatenate([zs, gz.ravel()])
    else:
        for i, (wc, _) in zip(WHEELS, WHEEL_STYLES):
            ax.scatter(traj[f"c{i}_x"][finite], traj[f"c{i}_y"][finite],
                       traj[f"c{i}_z"][finite], color=wc, s=3, alpha=0.5,
                       label=f"contact locus wheel {i}")
    ax.plot(traj["x"], traj["y"], traj["z"], color="black", linewidth=1.0,
            label="platform centre path")
    indices = _snapshot_indices(traj)
    _draw_snapshots(ax, traj, indices)
    dx, dy = box[1] - box[0], box[3] - box[2]
    dz = max(float(np.nanmax(zs) - np.nanmin(zs)), 1e-6)
    dz_box = 0.3 * max(dx, dy)
    ax.set_box_aspect((dx, dy, dz_box))
    ax.set_xlim(box[0], box[1])
    ax.set_ylim(box[2], box[3])
    ax.set_zlim(float(np.nanmin(zs)), float(np.nanmin(zs)) + dz)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.view_init(elev=28, azim=-60)
    for i, (wc, _) in zip(WHEELS, WHEEL_STYLES):
        ax.plot([], [], "o", color=wc, label=f"wheel {i} contact")
    ax.legend(loc="upper left", fontsize=7)
    exaggeration = dz_box / dz
    surface = (f"terrain surface from terrains/{run['scene']}.json "
               f"({describe_terrain(spec)})" if spec is not None else
               f"no terrains/{run['scene']}.json, so the contact-point locus is "
               "drawn without a terrain surface")
    caption = (
        "Fig. 5 — the paper shows snapshots of the robot crossing the rough "
        "terrain R1, the platform drawn as the triangle through its three "
        f"wheel-terrain contact points. This run: {_run_text(run)}, "
        f"{len(indices)} snapshots at t = "
        + ", ".join(f"{traj['t'][k]:.3g}" for k in indices)
        + f" s; {surface}; vertical scale exaggerated about "
        f"{fmt(exaggeration, 2)}×.")
    return save_figure(fig, ctx.out_dir, "fig05_snapshots",
                       "Fig. 5 — snapshots on the terrain", caption)


# ---------------------------------------------------------------- Fig. 6

def figure_locus(ctx):
    run, traj = _primary(ctx)
    spec = ctx.terrain(run["scene"])
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


def figure_normal_forces(ctx):
    fig, caption = _wheel_figure(
        ctx, "n{i}", "normal force N_i [N]",
        "Fig. 9 — the paper shows the three normal forces redistributing as "
        "the wheels cross the bumps, their sum balancing the weight.",
        total=True)
    return save_figure(fig, ctx.out_dir, "fig09_normal_forces",
                       "Fig. 9 — normal forces", caption)


def figure_longitudinal_traction(ctx):
    fig, caption = _wheel_figure(
        ctx, "t{i}_lon", "longitudinal traction [N]",
        "Fig. 10 — the paper shows the longitudinal traction each wheel must "
        "provide to climb and descend the bumps.")
    return save_figure(fig, ctx.out_dir, "fig10_longitudinal_traction",
                       "Fig. 10 — longitudinal traction", caption)


def figure_lateral_traction(ctx):
    fig, caption = _wheel_figure(
        ctx, "t{i}_lat", "lateral traction [N]",
        "Fig. 11 — the paper shows the lateral traction that keeps the wheels "
        "from side-slipping on the sloped terrain.")
    return save_figure(fig, ctx.out_dir, "fig11_lateral_traction",
                       "Fig. 11 — lateral traction", caption)


def figure_slip(ctx):
    run, traj = _primary(ctx)
    slips = np.concatenate([traj[f"slip{i}"] for i in WHEELS])
    log = bool(np.any(slips > 0))
    fig, _ = _wheel_figure(
        ctx, "slip{i}", "slip speed ‖s_i‖ [m/s]", "", log=log,
        absolute=True)
    finite = slips[np.isfinite(slips)]
    caption = (
        "Fig. 12 — the paper shows that the wheels roll with (near-)zero slip "
        "when friction suffices (μ = 0.5). This run: max slip "
        f"{fmt(float(finite.max()) if finite.size else math.nan)} m/s, median "
        f"{fmt(float(np.median(finite)) if finite.size else math.nan)} m/s"
        + ("" if log else " (all zero: linear axis)")
        + f" ({_run_text(run)}).")
    return save_figure(fig, ctx.out_dir, "fig12_slip",
                       "Fig. 12 — slip speeds", caption)


# ------------------------------------------------------------ Figs. 13-14

def trajectory_metrics(traj):
    """Traction and slip summaries of one run for the μ-sweep figures."""
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
    integral = float(np.sum(0.5 * (slip_sum[1:] + slip_sum[:-1]) * np.diff(t))) \
        if t.size > 1 else math.nan
    return {"mean_abs_lon": lon,
            "mean_total_traction": float(np.mean(total)) if ok.any() else math.nan,
            "total_slip": integral}


def _sweep_data(ctx):
    rows = sel.mu_sweep_rows(ctx.runs)
    ok = [r for r in rows if is_success(r) and ctx.trajectories.has(r)
          and ctx.trajectories.get(r) is not None]
    if not ok:
        raise MissingData("no successful mu_sweep run with a trajectory for "
                          "figures 13-14")
    metrics = {r["run_id"]: trajectory_metrics(ctx.trajectories.get(r)) for r in ok}
    failed = [r for r in rows if not is_success(r)]
    return ok, metrics, failed


def _per_method_curve(ax, ctx, ok, metrics, key):
    for method in sel.method_names(ok):
        mine = sorted((r["mu"], metrics[r["run_id"]][key]) for r in ok
                      if r["method"] == method)
        mus = sorted({m for m, _ in mine})
        vals = [float(np.nanmedian([v for m, v in mine if m == mu])) for mu in mus]
        colour, marker = ctx.styles[method]
        ax.plot(mus, vals, color=colour, marker=marker, label=method)


def _mark_failures(ax, ctx, failed):
    trans = blended_transform_factory(ax.transData, ax.transAxes)
    labelled = set()
    for k, r in enumerate(sorted(failed, key=lambda r: (r["mu"], r["method"]))):
        colour = ctx.styles[r["method"]][0]
        ax.plot([r["mu"]], [0.04 + 0.03 * (k % 3)], marker="x", color=colour,
                markersize=9, markeredgewidth=2, transform=trans, linestyle="none")
        if (r["mu"], r["status"]) not in labelled:
            labelled.add((r["mu"], r["status"]))
            ax.text(r["mu"], 0.14, " " + r["status"], rotation=90, fontsize=6.5,
                    ha="center", va="bottom", transform=trans, color="#333333")
    if failed:
        ax.plot([], [], "x", color="#444444", markeredgewidth=2,
                label="failed μ (status)")


def _mu_min_line(ax, rows):
    values = [r.get("mu_min") for r in rows]
    values = [v for v in values if isinstance(v, float) and math.isfinite(v)]
    if values:
        ax.axvline(float(np.median(values)), color="grey", linestyle=":",
                   label=f"μ_min ≈ {fmt(float(np.median(values)))}")


def _failed_text(failed):
    if not failed:
        return "no μ failed"
    return "failed: " + ", ".join(
        f"μ={fmt(r['mu'])} {r['method']} {r['status']}" for r in failed)


def figure_traction_vs_mu(ctx):
    ok, metrics, failed = _sweep_data(ctx)
    fig = new_figure(11, 4.4)
    ax_total, ax_wheel = fig.subplots(1, 2)
    _per_method_curve(ax_total, ctx, ok, metrics, "mean_total_traction")
    _mark_failures(ax_total, ctx, failed)
    _mu_min_line(ax_total, ok + failed)
    ax_total.set_xlabel("friction coefficient μ [-]")
    ax_total.set_ylabel("mean Σ_i ‖traction_i‖ [N]")
    ax_total.set_title("total traction per method")
    ax_total.legend(loc="upper right", fontsize=7)
    main = ctx.primary["method"] if ctx.primary is not None and any(
        r["method"] == ctx.primary["method"] for r in ok) else sel.method_names(ok)[0]
    mine = sorted((r for r in ok if r["method"] == main), key=lambda r: r["mu"])
    for i, (colour, style) in zip(WHEELS, WHEEL_STYLES):
        ax_wheel.plot([r["mu"] for r in mine],
                      [metrics[r["run_id"]]["mean_abs_lon"][i - 1] for r in mine],
                      color=colour, linestyle=style, marker="o", label=f"wheel {i}")
    ax_wheel.set_xlabel("friction coefficient μ [-]")
    ax_wheel.set_ylabel("mean |longitudinal traction| [N]")
    ax_wheel.set_title(f"per wheel, {main}")
    ax_wheel.legend(loc="best")
    best = [(r["mu"], metrics[r["run_id"]]["mean_total_traction"]) for r in mine]
    caption = (
        "Fig. 13 — the paper shows how the traction the wheels develop varies "
        "with the friction coefficient μ. This run: mean total traction "
        + ", ".join(f"{fmt(v)} N at μ={fmt(m)}" for m, v in best)
        + f" ({main}); {_failed_text(failed)}.")
    return save_figure(fig, ctx.out_dir, "fig13_traction_vs_mu",
                       "Fig. 13 — traction vs μ", caption)


def figure_total_slip_vs_mu(ctx):
    ok, metrics, failed = _sweep_data(ctx)
    fig = new_figure(8, 4.4)
    ax = fig.add_subplot()
    _per_method_curve(ax, ctx, ok, metrics, "total_slip")
    _mark_failures(ax, ctx, failed)
    _mu_min_line(ax, ok + failed)
    values = [metrics[r["run_id"]]["total_slip"] for r in ok]
    if spans_decades(values, 1.0):
        ax.set_yscale("log")
    ax.set_xlabel("friction coefficient μ [-]")
    ax.set_ylabel("total slip ∫Σ_i ‖s_i‖ dt [m]")
    ax.legend(loc="best", fontsize=7)
    pairs = sorted((r["mu"], metrics[r["run_id"]]["total_slip"]) for r in ok)
    caption = (
        "Fig. 14 — the paper shows the accumulated slip falling as μ grows. "
        "This run: " + ", ".join(f"{fmt(v)} m at μ={fmt(m)}" for m, v in pairs[:8])
        + ("…" if len(pairs) > 8 else "") + f"; {_failed_text(failed)}.")
    return save_figure(fig, ctx.out_dir, "fig14_total_slip_vs_mu",
                       "Fig. 14 — total slip vs μ", caption)


# ---------------------------------------------------------------- Fig. 15

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
        colour, marker = ctx.styles[run["method"]]
        ax.plot(traj["t"], positive(traj["drift"]), color=colour, marker=marker,
                markevery=0.1, label=f"{run['dae']} ({run['method']}, "
                f"Δt={fmt(run['dt'])} s"
                + (f", σ={fmt(run['sigma'])} 1/s)" if is_finite(run["sigma"]) else ")"))
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
    return save_figure(fig, ctx.out_dir, "fig15_stabilisation",
                       "Fig. 15 — constraint stabilisation", caption)
