"""quasiroll from Python: scenes, poses, quasi-static solves, simulations and
benchmark results (docs/python.md).

    import quasiroll
    scene = quasiroll.load_scene("bench/scenes/paper.yaml")
    traj, stats = quasiroll.run(scene, t_end=5)  # the default backends
    traj.plot(x="x", y="y")

Every result has the keys and columns of the CLI's outputs (docs/formats.md):
``pose`` and ``solve`` the ``--json`` documents, ``run`` the columns of
trajectory.csv and the keys of run.json. Vectors are numpy arrays; a value
the computation did not produce is ``None`` (JSON null), never zero.
Keyword names are the CLI's flag names with '-' written '_' (docs/cli.md).
"""

import io
import json
import os

import numpy as np

from ._quasiroll import GeometryError, Scene, SceneError, backends, commit, load_plugin
from ._quasiroll import load_scene as _load_scene
from . import _quasiroll

__all__ = ["Scene", "SceneError", "GeometryError", "load_scene", "pose",
           "solve", "step", "run", "backends", "load_runs", "commit"]


def load_scene(path):
    """Loads and validates a scene YAML file (docs/scenes.md)."""
    return _load_scene(os.fspath(path))


def _arrays(value):
    """JSON lists of numbers -> numpy arrays, recursively; a list holding
    only nulls (a value that was not computed) -> None."""
    if isinstance(value, dict):
        return {k: _arrays(v) for k, v in value.items()}
    if isinstance(value, list):
        if value and all(v is None for v in value):
            return None
        if all(isinstance(v, (int, float)) or v is None for v in value):
            return np.array([np.nan if v is None else v for v in value],
                            dtype=float)
        return [_arrays(v) for v in value]
    return value


def pose(scene):
    """The initial consistent configuration of `scene` (`quasiroll pose
    --json`): position, rpy, joint_angles (numpy), H_norm, contact_residual,
    contacts (list of 3 dicts: point, normal, psi, u_w, v_w)."""
    return _arrays(json.loads(_quasiroll._pose_json(scene)))


def _given_options(name, value):
    """A dict of backend options as the option texts `--nlp-opt` takes."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise ValueError(f"{name}: must be a dict of option name -> value, "
                         f"got {type(value).__name__}")
    out = {}
    for key, item in value.items():
        if isinstance(item, bool):
            item = "true" if item else "false"
        elif isinstance(item, float):
            item = repr(item)
        out[str(key)] = str(item)
    return out


def solve(scene, nlp=None, *, mu=None, eps=None, mode=None, nlp_tol=None,
          nlp_max_iter=None, nlp_options=None, sensitivities=False):
    """One quasi-static solve at the scene's initial configuration
    (`quasiroll solve --json`). Returns a dict: status, message, mu_min,
    twist, joint_rates, actuator_torques (numpy; None when the status is not
    OK), gap, iterations, residual, condition_number, wall_s, critical_wheel
    (1-based or None), contacts (list of 3 dicts of numpy arrays, or None)
    and ok (status == "OK"). The keywords are run()'s, with its rules.
    sensitivities=True (`solve --sensitivities`): also "sensitivities", a
    dict with the JSON's keys, each d<output>_d<input> and multiplier_values
    a numpy array (1-D for mu and eps, else rows = output, columns = input);
    None when the solve failed."""
    d = json.loads(_quasiroll._solve_json(
        scene, nlp or "", mu, eps, mode, nlp_tol, nlp_max_iter,
        _given_options("nlp_options", nlp_options), bool(sensitivities)))
    if d["status"] != "OK":
        d["contacts"] = None
    sens = d.pop("sensitivities", None)
    d = _arrays(d)
    if sensitivities:
        if sens is not None:
            sens = {k: np.array(v, dtype=float)
                    if k.startswith("d") or k == "multiplier_values" else v
                    for k, v in sens.items()}
        d["sensitivities"] = sens
    d["ok"] = d["status"] == "OK"
    return d


def step(scene, state=None, *, dt=None, coupling="zoh", dae=None,
         substeps=1, derivatives=True, nlp=None, mu=None, eps=None,
         mode=None, nlp_tol=None, nlp_max_iter=None, nlp_options=None):
    """One hold interval from `state` (21 values in the order of
    state_names; None: the scene's initial configuration) and its
    derivative: what a planner or an optimiser calls (docs/python.md,
    docs/model.md §7.9; `quasiroll solve --step-derivative --json`).
    dt: the interval (the scene's); coupling "zoh" (twist solved at the
    state and held) or "coupled" (re-solved at every RK stage); dae: the
    explicit fixed-step integrator (None: the projection RK, or the
    Baumgarte RK by its registry name); substeps: RK4 steps per interval.
    Returns a dict: status ("OK", "ONE_SIDED", "SINGULAR", ...), message,
    one_sided_constraints, state_names, rate_names, state, state_next
    (numpy; None without a value), drift, and the derivatives
    dstate_next_dstate (21 x 21), dstate_next_dmu, dstate_next_deps (21),
    dstate_next_drates (21 x 6) as numpy arrays (rows: state_next, columns:
    the input), None when derivatives=False or when they do not exist."""
    if state is not None:
        state = [float(v) for v in np.asarray(state, dtype=float).ravel()]
    return _quasiroll._step(
        scene, state, dt, coupling, dae or "", int(substeps), nlp or "", mu,
        eps, mode, nlp_tol, nlp_max_iter,
        _given_options("nlp_options", nlp_options), bool(derivatives))


def run(scene, nlp=None, dae=None, *, coupling="zoh", dt=None,
        t_end=None, mu=None, eps=None, mode=None, rk_method=None, sigma=None,
        tol=None, atol=None, nlp_tol=None, dae_index=None, substeps=None,
        contact_check=None, nlp_options=None, dae_options=None, as_frame=True,
        nlp_max_iter=None, locate_events=None, event_points=None,
        event_tolerance=None, locate_switches=None):
    """Simulates `scene` (`quasiroll run`). Returns (trajectory, stats):
    trajectory is a pandas DataFrame with the columns of trajectory.csv (or,
    with as_frame=False, a dict of numpy arrays), stats the run.json dict
    (status, stop_reason, t_reached, counters, wall_s, options, ...).
    Options left at None take the scene's value or the library default (nlp,
    dae: the backends registered as defaults, `quasiroll list`).
    nlp_max_iter: the iteration limit of each quasi-static solve (100).
    locate_events, event_points, event_tolerance: located stops at physical
    limits between samples (True, 3 points per interval, 1e-9 s).
    locate_switches: locate slide/stick switches and restart coupled
    integration there (True).
    nlp_options / dae_options: the backends' own options as a dict (name ->
    value, as `--nlp-opt` / `--dae-opt`; `quasiroll list --options` lists
    them); an unknown or ill-typed one raises ValueError naming it. The GIL
    is released while the simulation runs; Ctrl-C raises KeyboardInterrupt."""
    csv_text, run_json = _quasiroll._run_text(
        scene, nlp or "", dae or "", coupling, dt, t_end, mu, eps, mode, rk_method, sigma,
        tol, atol, nlp_tol, dae_index, substeps, contact_check, nlp_max_iter,
        _given_options("nlp_options", nlp_options),
        _given_options("dae_options", dae_options), locate_events,
        event_points, event_tolerance, locate_switches)
    stats = json.loads(run_json)
    if as_frame:
        import pandas as pd
        # round_trip: pandas' default parser is off by an ulp at times; the
        # files' 17 significant digits are meant to be read exactly.
        trajectory = pd.read_csv(io.StringIO(csv_text),
                                 dtype={"nlp_status": str},
                                 float_precision="round_trip")
    else:
        header, *rows = csv_text.splitlines()
        columns = header.split(",")
        cells = [row.split(",") for row in rows]
        trajectory = {}
        for i, name in enumerate(columns):
            values = [c[i] for c in cells]
            if name == "nlp_status":
                trajectory[name] = np.array(values, dtype=object)
            else:
                trajectory[name] = np.array(values, dtype=float)
    return trajectory, stats


def load_runs(directory):
    """runs.csv of a `quasiroll bench` output directory as a pandas DataFrame
    (docs/harness.md): empty fields (not applicable) and `nan` become NaN;
    text columns stay strings."""
    import pandas as pd
    path = os.path.join(os.fspath(directory), "runs.csv")
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path}: no runs.csv (run 'quasiroll bench' "
                                "first, or 'quasiroll merge' for shards)")
    text_columns = {"run_id", "suite_group", "scene", "terrain", "nlp", "dae",
                    "coupling", "rk_method", "status", "stop_reason",
                    "ref_kind", "ref_status", "ref_hash", "cause",
                    "cause_detail", "host", "cpu_model", "wall_s_all",
                    "nlp_options", "dae_options"}
    header = pd.read_csv(path, nrows=0).columns
    dtypes = {c: str for c in header if c in text_columns}
    return pd.read_csv(path, dtype=dtypes, keep_default_na=False,
                       na_values={c: ["", "nan"] for c in header
                                  if c not in text_columns},
                       float_precision="round_trip")
