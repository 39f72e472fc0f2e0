#!/usr/bin/python3
"""Writes a small synthetic but realistic quasiroll results directory.

    /usr/bin/python3 reports/make_fixture.py DIR [--seed N]

Contents (deterministic for a seed): runs.csv with a work-precision ladder
(3 methods x 3 Δt/tol rungs on the paper scene at μ = 0.5), a μ sweep
(2 methods x μ in {0.2, 0.3, 0.5, 0.8}; μ = 0.2 is below μ_min and fails with
INFEASIBLE_FRICTION), stability sweeps over Δt, σΔt and roughness with some
failures, and a method (ceres/rk-baumgarte/coupled) whose runs all fail;
trajectories/<run_id>.csv for every successful run; meta.json;
terrains/paper.json with a few Gaussian bumps.
"""

import argparse
import csv
import json
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from quasiroll_report.data import REQUIRED_COLUMNS, TRAJECTORY_COLUMNS  # noqa: E402

RUN_COLUMNS = ["run_id", "suite_group"] + REQUIRED_COLUMNS + ["mu_min", "roughness", "t_end"]

A, B, TRACK = 0.25, 0.25, 0.4       # robot geometry of bench/scenes/paper.yaml
WHEEL_RADIUS = 0.10                 # major + tube radius
SPIN = 0.6                          # wheel spin [rad/s]
MASS, G = 5.0, 9.8
T_END = 8.0
MU_MIN = 0.27

# method -> (order p, error constant, wall constant, drift level)
METHODS = {
    ("ipopt", "rk-baumgarte", "zoh"): (1.0, 2e-3, 0.9, 1e-6),
    ("newton", "rk-projection", "zoh"): (1.0, 1.5e-3, 0.25, 1e-13),
    ("slsqp", "ida", "coupled"): (2.0, 4e-2, 0.6, 1e-9),
}
FAILING_METHOD = ("ceres", "rk-baumgarte", "coupled")


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


def synth_trajectory(rng, terrain, dt, mu, error_scale, drift_level, t_end=T_END):
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
        slip = 1e-7 / mu * np.exp(4 * use) * (1 + 0.2 * rng.random(t.size))
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

def base_run(run_id, group, method, dt, mu, scene="paper"):
    nlp, dae, coupling = method
    return {"run_id": run_id, "suite_group": group, "scene": scene, "nlp": nlp,
            "dae": dae, "coupling": coupling, "dt": dt,
            "tol": 1e-6 if dae != "ida" else dt ** 2 * 1e-2,
            "sigma": 5.0 if dae == "rk-baumgarte" else "",
            "eps": 1e-8, "mu": mu, "seed": 1, "repeats": 3, "mu_min": MU_MIN,
            "roughness": "", "t_end": T_END}


def success_fields(rng, method, dt, drift_level):
    order, err_c, wall_c, _ = METHODS[method]
    err = err_c * dt ** order * (1 + 0.1 * rng.random())
    steps = int(round(T_END / dt))
    return {"status": "success", "stop_reason": "", "t_reached": T_END,
            "wall_s": wall_c * 0.05 / dt * (1 + 0.1 * rng.random()),
            "nlp_solves": steps * (4 if method[2] == "coupled" else 1),
            "nlp_iters": steps * 7, "rhs_evals": steps * 4, "steps": steps,
            "rejected_steps": 0, "err_pos_rms": err, "err_pos_max": 3 * err,
            "err_final": 2 * err, "err_rot_max": 5 * err,
            "err_force_rms": 400 * err, "err_slip": err / 10,
            "drift_max": drift_level * 1.4 * (dt / 0.05) ** 0.5,
            "drift_final": drift_level, "gap_max": 2e-7}


def failure_fields(status, t_reached, reason):
    return {"status": status, "stop_reason": reason, "t_reached": t_reached,
            "wall_s": 0.05, "nlp_solves": 3, "nlp_iters": 40, "rhs_evals": 12,
            "steps": 3, "rejected_steps": 1, "err_pos_rms": "nan",
            "err_pos_max": "nan", "err_final": "nan", "err_rot_max": "nan",
            "err_force_rms": "nan", "err_slip": "nan", "drift_max": "nan",
            "drift_final": "nan", "gap_max": ""}


def plan_runs():
    """(run dict without results, outcome) for the whole fixture suite."""
    plan = []
    ladders = {"rk-baumgarte": [0.2, 0.1, 0.05], "rk-projection": [0.2, 0.1, 0.05],
               "ida": [0.2, 0.1, 0.05]}
    for method in METHODS:
        for dt in ladders[method[1]]:
            plan.append((base_run(f"wp-{method[0]}-{method[1]}-dt{dt:g}",
                                  "work_precision", method, dt, 0.5), None))
    for dt in (0.2, 0.1):
        plan.append((base_run(f"wp-ceres-dt{dt:g}", "work_precision",
                              FAILING_METHOD, dt, 0.5),
                     ("SOLVER_FAILURE", 0.0, "t=0, ceres: no convergence, iters=200")))
    for method in list(METHODS)[:2]:
        for mu in (0.2, 0.3, 0.5, 0.8):
            outcome = None if mu > MU_MIN else (
                "INFEASIBLE_FRICTION", 0.0,
                f"t=0, mu={mu:g} < mu_min={MU_MIN:g}, wheel 1")
            plan.append((base_run(f"mu-{method[0]}-mu{mu:g}", "mu_sweep", method,
                                  0.1, mu), outcome))
    for method in list(METHODS) + [FAILING_METHOD]:
        for dt in (0.2, 0.4, 0.8):
            run = base_run(f"stab-{method[0]}-{method[1]}-dt{dt:g}", "stability_dt",
                           method, dt, 0.5)
            outcome = None
            if method == FAILING_METHOD:
                outcome = ("convergence_failure", 0.0, "t=0, Newton diverged")
            elif dt >= 0.8 and method[1] != "ida":
                outcome = ("constraint_failure", 2.4, "t=2.4, ||H|| > 1e-3")
            elif dt >= 0.4 and method[1] == "ida":
                outcome = ("step_size_too_small", 1.1, "t=1.1, IDA_TOO_MUCH_WORK")
            plan.append((run, outcome))
    baum = list(METHODS)[0]
    for sigma in (5.0, 15.0, 30.0):
        run = base_run(f"stab-sigma{sigma:g}", "stability_sigma", baum, 0.1, 0.5)
        run["sigma"] = sigma
        outcome = ("constraint_failure", 0.9, "t=0.9, sigma*dt beyond RK4 limit") \
            if sigma * 0.1 > 2.785 else None
        plan.append((run, outcome))
    for method in list(METHODS)[:2]:
        for rough in (0.01, 0.02, 0.04):
            run = base_run(f"rough-{method[0]}-r{rough:g}", "stability_roughness",
                           method, 0.1, 0.5, scene="rough")
            run["roughness"] = rough
            outcome = ("LIFT_OFF", 3.3, "t=3.3, wheel 2 lifts off") if rough > 0.03 else None
            plan.append((run, outcome))
    return plan


def build_fixture(out_dir, seed=7):
    """Write the fixture into out_dir (created); return out_dir."""
    rng = np.random.default_rng(seed)
    os.makedirs(os.path.join(out_dir, "trajectories"), exist_ok=True)
    os.makedirs(os.path.join(out_dir, "terrains"), exist_ok=True)
    terrain = make_terrain(rng)
    with open(os.path.join(out_dir, "terrains", "paper.json"), "w") as handle:
        json.dump(terrain, handle, indent=1)
    rows = []
    for run, outcome in plan_runs():
        method = (run["nlp"], run["dae"], run["coupling"])
        if outcome is None:
            drift = METHODS[method][3]
            run.update(success_fields(rng, method, run["dt"], drift))
            order, err_c, _, _ = METHODS[method]
            cols = synth_trajectory(rng, terrain, run["dt"], run["mu"],
                                    err_c * run["dt"] ** order, drift)
            write_trajectory(os.path.join(out_dir, "trajectories",
                                          f"{run['run_id']}.csv"), cols)
        else:
            run.update(failure_fields(*outcome))
        rows.append(run)
    with open(os.path.join(out_dir, "runs.csv"), "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=RUN_COLUMNS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: _cell(row.get(k, "")) for k in RUN_COLUMNS})
    write_meta(out_dir, seed)
    return out_dir


def _cell(value):
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.10g}"
    return value


def write_meta(out_dir, seed):
    meta = {"commit": "0123abc (fixture)",
            "machine": {"hostname": "fixture-host", "cpu": "synthetic CPU", "cores": 4},
            "library_versions": {"eigen": "3.4.0", "ipopt": "3.14.10",
                                 "nlopt": "2.7.1", "ceres": "2.1.0",
                                 "sundials": "6.4.1"},
            "numerical_libraries": {"blas": "/fixture/blas/libblas.so.3",
                                    "lapack": "/fixture/lapack/liblapack.so.3"},
            "suite": "fixture", "suite_hash": f"seed-{seed}",
            "start_time": "2024-01-01T00:00:00Z", "end_time": "2024-01-01T00:05:00Z",
            "options": {"t_end": T_END, "repeats": 3}}
    with open(os.path.join(out_dir, "meta.json"), "w") as handle:
        json.dump(meta, handle, indent=1)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out_dir", metavar="DIR")
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args(argv)
    print(os.path.abspath(build_fixture(args.out_dir, args.seed)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
