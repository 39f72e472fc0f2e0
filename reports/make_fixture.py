#!/usr/bin/python3
"""Writes a small synthetic but realistic quasiroll results directory.

    /usr/bin/python3 reports/make_fixture.py DIR [--seed N]

Contents (deterministic for a seed): runs.csv with a zoh work-precision
ladder (3 methods x 3 Δt on the paper scene, μ = 0.5, T_END s) and a coupled
ladder on a shorter problem (T_END_CPL s: must never share a chart with the
first); a μ sweep on `paper` and `paper_pvc` (pvc slips ~1000x less and needs
μ >= 0.43; stops report a different μ_min on purpose); stability groups
stability_dt (with a blow-up that ends in INFEASIBLE_FRICTION but is classed
numerical/drift_blowup), stability_sigma_dt, stability_mu and
stability_roughness; a method (ceres/rk-baumgarte/coupled) whose runs all
fail; an option variant of newton/rk-projection/zoh in the zoh ladder
(VARIANT_OPTIONS: faster at the same error); the `method` column and the
issue-#14 columns (timing spread, causes, ref_mu_min, ref_err_est,
qs_inertia_ratio, kkt_residual, host) unless --legacy; trajectories for every
successful run; meta.json with a suite file and scene under inputs/;
terrains/*.json.
"""

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from quasiroll_report.data import (NUMERIC_COLUMNS, REQUIRED_COLUMNS,  # noqa: E402
                                   RUNS_COLUMNS, TRAJECTORY_COLUMNS, parse_number)

# The columns of runs.csv before issue #14 (--legacy writes only these).
LEGACY_COLUMNS = {"run_id", "suite_group", "mu_min", "roughness", "t_end",
                  *REQUIRED_COLUMNS}

A, B, TRACK = 0.25, 0.25, 0.4       # robot geometry of bench/scenes/paper.yaml
WHEEL_RADIUS = 0.10                 # major + tube radius
SPIN = 0.6                          # wheel spin [rad/s]
MASS, G = 5.0, 9.8
T_END = 8.0
T_END_CPL = 2.0                     # the coupled ladder is a shorter problem
MU_MIN = 0.27
# The friction each scene needs along its reference (ref_mu_min), and what a
# stop reports (mu_min at the stop: a different number on purpose, so a test
# can tell which one a figure used).
REF_MU_MIN = {"paper": 0.27, "paper_pvc": 0.43, "rough": 0.3}
STOP_MU_MIN = 0.25
PVC_SLIP_FACTOR = 1e-3              # pvc slips ~1000x less than paper mode
REF_ERR_EST = {T_END: 2e-9, T_END_CPL: 5e-10}

# method -> (order p, error constant, wall constant, drift level)
METHODS = {
    ("ipopt", "rk-baumgarte", "zoh"): (1.0, 2e-3, 0.9, 1e-6),
    ("newton", "rk-projection", "zoh"): (1.0, 1.5e-3, 0.25, 1e-13),
    ("slsqp", "ida", "coupled"): (2.0, 4e-2, 0.6, 1e-9),
}
FAILING_METHOD = ("ceres", "rk-baumgarte", "coupled")
# An option variant of a pair (docs/harness.md, "Method identity"): same
# error, VARIANT_WALL x the wall time, so the 'fastest' findings must name
# it by its full method id and never credit the pair with its speed.
VARIANT = ("newton", "rk-projection", "zoh")
VARIANT_OPTIONS = [("projection_tolerance", "1e-08")]
VARIANT_WALL = 0.5


# ------------------------------------------------------------------ terrain

def make_terrain(rng, count=6):
    bumps = []
    for _ in range(count):
        bumps.append([round(float(rng.uniform(-0.03, 0.035)), 4),
                      round(float(rng.uniform(-0.2, 1.2)), 3),
                      round(float(rng.uniform(-0.5, 0.5)), 3),
                      round(float(rng.uniform(0.2, 0.4)), 3)])
    return {"type": "gaussians", "bumps": bumps}


def height(terrain, x, y):
    h = np.zeros_like(np.asarray(x, float))
    for amplitude, bx, by, sigma in terrain["bumps"]:
        h = h + amplitude * np.exp(-((x - bx) ** 2 + (y - by) ** 2) / (2 * sigma ** 2))
    return h


# -------------------------------------------------------------- trajectory

def _wheel_offsets():
    return [(A, 0.0), (-B, TRACK / 2), (-B, -TRACK / 2)]


def synth_trajectory(rng, terrain, dt, mu, error_scale, drift_level, t_end=T_END,
                     slip_factor=1.0):
    """Dict of columns for one run (numbers) plus nlp_status strings."""
    t = np.arange(0.0, t_end + 1e-9, dt)
    speed = SPIN * WHEEL_RADIUS
    wobble = error_scale * np.sin(1.3 * t)
    x = speed * t + wobble
    y = 0.03 * np.sin(0.4 * t) + 0.5 * wobble
    yaw = 0.03 * np.cos(0.4 * t)
    cols = {"t": t}
    contacts = []
    for dx, dy in _wheel_offsets():
        cx = x + np.cos(yaw) * dx - np.sin(yaw) * dy
        cy = y + np.sin(yaw) * dx + np.cos(yaw) * dy
        contacts.append((cx, cy, height(terrain, cx, cy)))
    front_z, left_z, right_z = (c[2] for c in contacts)
    pitch = np.arctan2((left_z + right_z) / 2 - front_z, A + B)
    roll = np.arctan2(left_z - right_z, TRACK)
    z = (front_z + left_z + right_z) / 3 + WHEEL_RADIUS + 0.05
    grad = np.gradient
    cols.update(x=x, y=y, z=z, roll=roll, pitch=pitch, yaw=yaw,
                vx=grad(x, t), vy=grad(y, t), vz=grad(z, t),
                wx=grad(roll, t), wy=grad(pitch, t), wz=grad(yaw, t))
    for k, name in enumerate(["phi1", "alpha1", "delta2", "alpha2", "delta3", "alpha3"]):
        cols[name] = (SPIN * t) if name.startswith("alpha") else 0.02 * np.sin(0.3 * t + k)
    weight = MASS * G
    shares = np.array([0.4, 0.3, 0.3])
    for i, (cx, cy, cz) in enumerate(contacts, start=1):
        tilt = (-1 if i == 1 else 1) * 3.0 * np.sin(pitch) + (
            0 if i == 1 else (1 if i == 2 else -1)) * 2.0 * np.sin(roll)
        normal = weight * shares[i - 1] * (1 + tilt) + rng.normal(0, 0.05, t.size)
        scrub = 1 + 0.15 / mu      # less friction → more scrubbing at the rear
        lon = weight * shares[i - 1] * np.sin(pitch) + 0.4 * np.sin(0.9 * t + i)
        lat = scrub * (weight * shares[i - 1] * np.sin(roll) + 0.2 * np.cos(0.7 * t + i))
        use = np.hypot(lon, lat) / (mu * normal)
        slip = slip_factor * 1e-7 / mu * np.exp(4 * use) * (1 + 0.2 * rng.random(t.size))
        cols.update({f"c{i}_x": cx, f"c{i}_y": cy, f"c{i}_z": cz, f"n{i}": normal,
                     f"t{i}_lon": lon, f"t{i}_lat": lat, f"slip{i}": slip,
                     f"use{i}": use})
    growth = 1 - np.exp(-t / 2.0)
    cols["drift"] = drift_level * (0.2 + growth) * (1 + 0.3 * rng.random(t.size))
    cols["gap_max"] = 1e-7 * (1 + rng.random(t.size))
    cols["nlp_status"] = ["OK"] * t.size
    cols["nlp_iters"] = rng.integers(3, 12, t.size).astype(float)
    return cols


def write_trajectory(path, cols):
    n = len(cols["t"])
    with open(path, "w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(TRAJECTORY_COLUMNS)
        for k in range(n):
            row = []
            for name in TRAJECTORY_COLUMNS:
                value = cols[name][k]
                row.append(value if isinstance(value, str) else
                           ("nan" if not math.isfinite(value) else f"{value:.17g}"))
            writer.writerow(row)


# -------------------------------------------------------------------- runs

def base_run(run_id, group, method, dt, mu, scene="paper", t_end=T_END):
    nlp, dae, coupling = method
    return {"run_id": run_id, "suite_group": group, "scene": scene, "nlp": nlp,
            "dae": dae, "coupling": coupling, "dt": dt,
            "tol": 1e-6 if dae != "ida" else dt ** 2 * 1e-2,
            # The harness writes the shorthand for every row; only the
            # integrators whose option table has baumgarte_sigma use it.
            "sigma": 5.0, "substeps": 1,
            "eps": 1e-8, "mu": mu, "seed": 1, "repeats": 3, "mu_min": "",
            "roughness": "", "t_end": t_end, "terrain": scene, "rk_method": "rk4",
            "host": "fixture-host", "cpu_model": "synthetic CPU"}


def method_id(run):
    """runs.csv `method` as the harness writes it: non-default integrator
    options (here baumgarte_sigma of the Baumgarte integrator and the
    variant's options) sorted by name in brackets."""
    options = list(run.get("_options", []))
    if run["dae"] == "rk-baumgarte" and run["sigma"] != 5.0:
        options.append(("baumgarte_sigma", f"{run['sigma']:g}"))
    listed = ",".join(f"{k}={v}" for k, v in sorted(options))
    return (f"{run['nlp']}/{run['dae']}" + (f"[{listed}]" if listed else "")
            + f"/{run['coupling']}")


def dae_options_json(run):
    """runs.csv `dae_options`: the integrator's whole option table as used
    (only the integrators with a Baumgarte gain have baumgarte_sigma)."""
    table = {"rk-baumgarte": {"baumgarte_sigma": run["sigma"], "rk_method": "rk4"},
             "rk-projection": {"projection_tolerance": 1e-12, "rk_method": "rk4"},
             "ida": {"baumgarte_sigma": run["sigma"], "dae_index": 2}}[run["dae"]]
    table = dict(table)
    for key, value in run.get("_options", []):
        table[key] = float(value)
    return json.dumps(table, sort_keys=True, separators=(",", ":"))


def ref_hash(run):
    """The fixture's stand-in for the harness's reference hash: one per
    problem (scene, μ, roughness, t_end)."""
    text = f"{run['scene']}|{run['mu']}|{run['roughness']}|{run['t_end']}"
    value = 0xcbf29ce484222325
    for byte in text.encode():
        value = ((value ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"{value:016x}"


def success_fields(rng, method, dt, drift_level, t_end=T_END):
    order, err_c, wall_c, _ = METHODS[method]
    err = err_c * dt ** order * (1 + 0.1 * rng.random())
    steps = int(round(t_end / dt))
    drift_max = drift_level * 1.4 * (dt / 0.05) ** 0.5
    return {"status": "success", "stop_reason": "", "t_reached": t_end,
            "wall_s": wall_c * 0.05 / dt * (1 + 0.1 * rng.random()) * t_end / T_END,
            "nlp_solves": steps * (4 if method[2] == "coupled" else 1),
            "nlp_iters": steps * 7, "rhs_evals": steps * 4, "steps": steps,
            "rejected_steps": 0, "err_pos_rms": err, "err_pos_max": 3 * err,
            "err_final": 2 * err, "err_rot_max": 5 * err,
            "err_force_rms": 400 * err, "err_slip": err / 10,
            "drift_max": drift_max, "drift_final": drift_level, "gap_max": 2e-7,
            "drift_step_max": step_drift(method, dt, drift_max)}


def step_drift(method, dt, drift_max):
    """drift_step_max (docs/model.md §8.10): in zoh the hold leaves the
    manifold by ~5.6e-4 Δt² per interval (paper scene: 1.41e-6 at 0.05 s),
    which projection methods remove and rk-baumgarte shows in its samples;
    coupled methods only their truncation (here 100x the samples')."""
    _, dae, coupling = method
    if dae == "rk-baumgarte":
        return drift_max
    return 5.6e-4 * dt ** 2 if coupling == "zoh" else 100 * drift_max


def failure_fields(status, t_reached, reason, cause="", detail=""):
    return {"status": status, "stop_reason": reason, "t_reached": t_reached,
            "cause": cause, "cause_detail": detail,
            "wall_s": 0.05, "nlp_solves": 3, "nlp_iters": 40, "rhs_evals": 12,
            "steps": 3, "rejected_steps": 1, "err_pos_rms": "nan",
            "err_pos_max": "nan", "err_final": "nan", "err_rot_max": "nan",
            "err_force_rms": "nan", "err_slip": "nan", "drift_max": "nan",
            "drift_final": "nan", "gap_max": ""}


def plan_runs():
    """(run dict without results, outcome) for the whole fixture suite.

    outcome = None (success) or (status, t_reached, reason, cause, detail)."""
    plan = []
    ladders = {"rk-baumgarte": [0.2, 0.1, 0.05], "rk-projection": [0.2, 0.1, 0.05],
               "ida": [0.2, 0.1, 0.05]}
    for method in METHODS:
        for dt in ladders[method[1]]:
            plan.append((base_run(f"wp-{method[0]}-{method[1]}-dt{dt:g}",
                                  "work_precision", method, dt, 0.5), None))
    # The coupled ladder of the default suite is a shorter problem (5 s there,
    # T_END_CPL here): its runs must never share a chart with the ones above.
    for dt in ladders[VARIANT[1]]:
        run = base_run(f"wpv-{VARIANT[0]}-{VARIANT[1]}-dt{dt:g}", "work_precision",
                       VARIANT, dt, 0.5)
        run["_options"] = VARIANT_OPTIONS
        plan.append((run, None))
    for method in list(METHODS)[:2]:
        cpl = (method[0], method[1], "coupled")
        for dt in (0.1, 0.05):
            plan.append((base_run(f"wpc-{cpl[0]}-{cpl[1]}-dt{dt:g}", "work_precision_cpl",
                                  cpl, dt, 0.5, t_end=T_END_CPL), None))
    for dt in (0.2, 0.1):
        plan.append((base_run(f"wp-ceres-dt{dt:g}", "work_precision",
                              FAILING_METHOD, dt, 0.5),
                     ("SOLVER_FAILURE", 0.0, "t=0, ceres: no convergence, iters=200",
                      "numerical", "solver_failure")))
    for scene in ("paper", "paper_pvc"):
        for method in list(METHODS)[:2]:
            for mu in (0.2, 0.3, 0.5, 0.8):
                need = REF_MU_MIN[scene]
                outcome = None if mu > need else (
                    "INFEASIBLE_FRICTION", 0.0,
                    f"t=0, mu={mu:g} < mu_min={STOP_MU_MIN:g}, wheel 1",
                    "physical", "friction_limit")
                tag = "" if scene == "paper" else "pvc-"
                plan.append((base_run(f"mu-{tag}{method[0]}-mu{mu:g}", "mu_sweep", method,
                                      0.1, mu, scene=scene), outcome))
    for method in list(METHODS) + [FAILING_METHOD]:
        for dt in (0.2, 0.4, 0.8):
            run = base_run(f"stab-{method[0]}-{method[1]}-dt{dt:g}", "stability_dt",
                           method, dt, 0.5)
            outcome = None
            if method == FAILING_METHOD:
                outcome = ("SOLVER_FAILURE", 0.0, "t=0, Newton diverged",
                           "numerical", "solver_failure")
            elif dt >= 0.8 and method[1] != "ida":
                # What the harness used to show as a friction limit: a blow-up
                # that ends in a quasi-static INFEASIBLE_FRICTION.
                outcome = ("INFEASIBLE_FRICTION", 2.4,
                           "t=2.4, mu=0.5 < mu_min=6.3, wheel 2",
                           "numerical", "drift_blowup")
            elif dt >= 0.4 and method[1] == "ida":
                outcome = ("step_size_too_small", 1.1, "t=1.1, IDA_TOO_MUCH_WORK",
                           "numerical", "integrator_failure")
            plan.append((run, outcome))
    baum = list(METHODS)[0]
    for sigma in (5.0, 15.0, 30.0):
        run = base_run(f"stab-sigma{sigma:g}", "stability_sigma_dt", baum, 0.1, 0.5)
        run["sigma"] = sigma
        outcome = ("DEGENERATE_CONTACT", 0.9, "t=0.9, sigma*dt beyond RK4 limit",
                   "numerical", "baumgarte_instability") if sigma * 0.1 > 2.785 else None
        plan.append((run, outcome))
    # An integrator without a Baumgarte gain in the σ group: σ is no
    # parameter of its, so the σ·Δt chart leaves it out (and says so).
    plan.append((base_run("stab-sigma-proj", "stability_sigma_dt", list(METHODS)[1],
                          0.1, 0.5), None))
    newton = list(METHODS)[1]
    for scene in ("paper", "paper_pvc"):
        for mu in (0.1, 0.3, 0.5):
            outcome = None if mu > REF_MU_MIN[scene] else (
                "INFEASIBLE_FRICTION", 0.0, f"t=0, mu={mu:g} < mu_min, wheel 1",
                "physical", "friction_limit")
            plan.append((base_run(f"stabmu-{scene}-mu{mu:g}", "stability_mu", newton,
                                  0.1, mu, scene=scene), outcome))
    for method in list(METHODS)[:2]:
        for rough in (0.01, 0.02, 0.04):
            run = base_run(f"rough-{method[0]}-r{rough:g}", "stability_roughness",
                           method, 0.1, 0.5, scene="rough")
            run["roughness"] = rough
            outcome = ("LIFT_OFF", 3.3, "t=3.3, wheel 2 lifts off",
                       "physical", "lift_off") if rough > 0.03 else None
            plan.append((run, outcome))
    return plan


def trust_fields(run, rng):
    """The issue-#14 columns of one row (timing spread over 3 repeats, ...)."""
    t_end = float(run["t_end"])
    fields = {"ref_hash": ref_hash(run), "t_reached_frac": run["t_reached"] / t_end,
              "ref_mu_min": REF_MU_MIN.get(run["scene"], MU_MIN),
              "ref_err_est": REF_ERR_EST.get(t_end, 1e-9),
              "qs_inertia_ratio": (0.08 if run["scene"] == "rough" else 0.004)
              * (1 + 0.1 * rng.random()) if run["status"] == "success" else "",
              "kkt_residual": 1e-11 * (1 + rng.random()) if run["status"] == "success" else ""}
    if run["status"] == "success":  # pvc never slides; creep ~ eps (model.md §7.5)
        pvc = run["scene"].endswith("pvc")
        fields["sliding_distance"] = 0.0 if pvc else 2.2e-4 * (1 + 0.1 * rng.random())
        fields["creep_distance"] = (30.0 if pvc else 40.0) * run["eps"] * (1 + 0.1 * rng.random())
    wall = float(run["wall_s"])
    repeats = [wall * 1.3, wall, wall * 1.08]
    fields.update({"wall_s_all": ";".join(f"{w:.6g}" for w in repeats),
                   "wall_s_min": min(repeats), "wall_s_max": max(repeats),
                   "wall_s_median": sorted(repeats)[1]})
    fields["wall_per_sim_s"] = fields["wall_s_median"] / run["t_reached"] \
        if run["t_reached"] > 0 else ""
    if run["status"] == "success":
        run["cause"] = run["cause_detail"] = ""
    if run["status"] == "INFEASIBLE_FRICTION":
        run["mu_min"] = STOP_MU_MIN
    return fields


def write_inputs(out_dir):
    """A suite file and its scene file, as the harness's meta.json names them."""
    inputs = os.path.join(out_dir, "inputs")
    os.makedirs(os.path.join(inputs, "scenes"), exist_ok=True)
    with open(os.path.join(inputs, "scenes", "paper.yaml"), "w") as handle:
        handle.write("name: paper\nmode: paper\nmu: 0.5\n")
    suite = os.path.join(inputs, "fixture.yaml")
    with open(suite, "w") as handle:
        handle.write("name: fixture\nscenes:\n  - {name: paper, file: scenes/paper.yaml}\n"
                     "  - {name: paper_pvc, file: scenes/paper.yaml, overrides: {mode: pvc}}\n")
    return suite


# Two located stick/slide switches per run, at these fractions of t_end
# (switches/<run_id>.csv, docs/formats.md); legacy outputs have no such file.
SWITCH_FRACTIONS = ((0.3, 1, "stick", "slide"), (0.6, 3, "slide", "stick"))
CREEP_REVERSAL_FRACTION = 0.45  # and one creep reversal, wheel 3
SOLUTION_JUMP_FRACTION = 0.5  # and one solution jump, all three wheels


def write_switches(path, t_end):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as handle:
        handle.write("t,wheel,from,to,located,t_lower,t_upper,kind\n")
        for fraction, wheel, before, after in SWITCH_FRACTIONS:
            t = fraction * t_end
            handle.write(f"{t!r},{wheel},{before},{after},true,{t - 1e-9!r},{t!r},switch\n")
        # One creeping wheel's slip reversal (docs/formats.md, kind).
        t = CREEP_REVERSAL_FRACTION * t_end
        handle.write(f"{t!r},3,stick,stick,true,{t - 1e-9!r},{t!r},creep_reversal\n")
        # One solution jump: an event per wheel, one bracket (kind).
        t = SOLUTION_JUMP_FRACTION * t_end
        for wheel in (1, 2, 3):
            handle.write(f"{t!r},{wheel},slide,slide,true,{t - 1e-9!r},{t!r},"
                         "solution_jump\n")


def build_fixture(out_dir, seed=7, legacy=False):
    """Write the fixture into out_dir (created); return out_dir. legacy=True
    writes runs.csv without the issue-#14 columns (older harness output)."""
    rng = np.random.default_rng(seed)
    os.makedirs(os.path.join(out_dir, "trajectories"), exist_ok=True)
    os.makedirs(os.path.join(out_dir, "terrains"), exist_ok=True)
    terrain = make_terrain(rng)
    with open(os.path.join(out_dir, "terrains", "paper.json"), "w") as handle:
        json.dump(terrain, handle, indent=1)
    rows = []
    for run, outcome in plan_runs():
        method = (run["nlp"], run["dae"], run["coupling"])
        base = (method[0], method[1], "zoh") if method not in METHODS else method
        if outcome is None:
            drift = METHODS[base][3]
            run.update(success_fields(rng, base, run["dt"], drift, run["t_end"]))
            if run.get("_options"):
                run["wall_s"] *= VARIANT_WALL
            order, err_c, _, _ = METHODS[base]
            cols = synth_trajectory(rng, terrain, run["dt"], run["mu"],
                                    err_c * run["dt"] ** order, drift, run["t_end"],
                                    PVC_SLIP_FACTOR if run["scene"] == "paper_pvc" else 1.0)
            write_trajectory(os.path.join(out_dir, "trajectories",
                                          f"{run['run_id']}.csv"), cols)
            if not legacy:
                write_switches(os.path.join(out_dir, "switches",
                                            f"{run['run_id']}.csv"), run["t_end"])
        else:
            run.update(failure_fields(*outcome))
        run.update(trust_fields(run, rng))
        run["method"] = method_id(run)
        run["dae_options"] = dae_options_json(run)
        rows.append(run)
    columns = runs_csv_columns(rows, legacy)
    with open(os.path.join(out_dir, "runs.csv"), "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _cell(k, row.get(k, "")) for k in columns})
    for scene in ("paper_pvc", "rough"):
        with open(os.path.join(out_dir, "terrains", f"{scene}.json"), "w") as handle:
            json.dump(terrain, handle, indent=1)
    backends = {kind: sorted({row[kind] for row in rows}) for kind in ("nlp", "dae")}
    write_meta(out_dir, seed, write_inputs(out_dir), backends)
    return out_dir


def runs_csv_columns(rows, legacy):
    """The schema's columns (bench/io/runs_columns.tsv, in runs.csv order)
    that the fixture fills; with legacy only those of older harnesses."""
    return [c for c in RUNS_COLUMNS if any(c in row for row in rows)
            and (not legacy or c in LEGACY_COLUMNS)]


def _cell(column, value):
    if column in NUMERIC_COLUMNS and isinstance(value, str):
        parse_number(value)  # ValueError: the schema says a number
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.10g}"
    return value


def write_meta(out_dir, seed, suite_path, backends):
    meta = {"commit": "0123abc (fixture)",
            "machine": {"hostname": "fixture-host", "cpu": "synthetic CPU", "cores": 4},
            "library_versions": {"eigen": "3.4.0", "ipopt": "3.14.10",
                                 "nlopt": "2.7.1", "ceres": "2.1.0",
                                 "sundials": "6.4.1"},
            "numerical_libraries": {"blas": "/fixture/blas/libblas.so.3",
                                    "lapack": "/fixture/lapack/liblapack.so.3"},
            "suite": {"name": "fixture", "path": suite_path,
                      "absolute_path": os.path.abspath(suite_path)},
            "suite_hash": f"seed-{seed}",
            "start_time": "2024-01-01T00:00:00Z", "end_time": "2024-01-01T00:05:00Z",
            "options": {"t_end": T_END, "repeats": 3},
            # The build's registered backends, as the harness writes them.
            "backends": {kind: [{"name": name, "family": "fixture"} for name in names]
                         for kind, names in backends.items()}}
    with open(os.path.join(out_dir, "meta.json"), "w") as handle:
        json.dump(meta, handle, indent=1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", metavar="DIR")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--legacy", action="store_true",
                        help="leave out the issue-#14 runs.csv columns")
    args = parser.parse_args(argv)
    print(os.path.abspath(build_fixture(args.out_dir, args.seed, args.legacy)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
