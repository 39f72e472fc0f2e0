"""The Python module `quasiroll` (bench/python, docs/python.md), run by ctest
under /usr/bin/python3 -m pytest with PYTHONPATH pointing at the built
package. QUASIROLL_BINARY (the CLI) and QUASIROLL_SOURCE_DIR come from
ctest. Each result is checked against the CLI's output for the same input,
or against a physical value with its origin named."""
import csv
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import quasiroll

SRC = os.environ.get("QUASIROLL_SOURCE_DIR",
                     os.path.join(os.path.dirname(__file__), "..", ".."))
BIN = os.environ.get("QUASIROLL_BINARY", "")
SCENES = os.path.join(SRC, "bench", "scenes")


def scene(name):
    return quasiroll.load_scene(os.path.join(SCENES, name + ".yaml"))


def cli_json(*args):
    out = subprocess.run([BIN, *args, "--json"], capture_output=True,
                         text=True, check=False)
    return json.loads(out.stdout)


def test_backends_list_the_builtins():
    b = quasiroll.backends()
    assert "newton" in b["nlp"] and "rk-projection" in b["dae"]
    assert re.fullmatch(r"[0-9a-f]{12}(-dirty)?|unknown", quasiroll.commit)


def test_load_scene_and_errors():
    s = scene("incline10")
    assert (s.name, s.mode, s.mu, s.dt, s.t_end) == ("incline10", "pvc", 0.5,
                                                     0.05, 10)
    with pytest.raises(quasiroll.SceneError, match="no_such.yaml"):
        quasiroll.load_scene(os.path.join(SCENES, "no_such.yaml"))
    with pytest.raises(ValueError, match="mu: must be a finite number > 0"):
        s.mu = 0
    assert s.mu == 0.5


@pytest.mark.skipif(not BIN, reason="QUASIROLL_BINARY not set")
def test_pose_equals_cli():
    p = quasiroll.pose(scene("paper"))
    c = cli_json("pose", "--scene", os.path.join(SCENES, "paper.yaml"))
    assert isinstance(p["position"], np.ndarray)
    np.testing.assert_array_equal(p["position"], c["position"])
    np.testing.assert_array_equal(p["contacts"][2]["point"],
                                  c["contacts"][2]["point"])


def test_solve_flat_matches_statics():
    # Flat ground, paper mode, COM midway between front and rear axles
    # (a = b): the front wheel carries m g / 2, each rear wheel m g / 4
    # (statics; scenes/flat.yaml: m = 5 kg, g = 9.8).
    r = quasiroll.solve(scene("flat"))
    assert r["ok"] and r["status"] == "OK"
    n = [c["normal_force"] for c in r["contacts"]]
    np.testing.assert_allclose(n, [24.5, 12.25, 12.25], rtol=1e-12)
    assert r["critical_wheel"] is None  # none: null, not 0
    assert isinstance(r["twist"], np.ndarray) and r["twist"].shape == (6,)


@pytest.mark.skipif(not BIN, reason="QUASIROLL_BINARY not set")
def test_solve_sensitivities_match_resolves_and_cli():
    # solve(sensitivities=True): numpy arrays named as the CLI's JSON keys
    # (docs/cli.md), rows = outputs, columns = inputs.
    r = quasiroll.solve(scene("paper"), "newton", sensitivities=True)
    s = r["sensitivities"]
    assert s["status"] == "OK" and not s["one_sided"]
    assert s["method"] == "ift-kkt+central-fd"
    assert len(s["state_names"]) == 21 and s["state_names"][15] == "phi1"
    assert s["dtwist_dstate"].shape == (6, 21)
    assert s["dtwist_dmu"].shape == (6,) and s["dtwist_deps"].shape == (6,)
    assert s["dtwist_drates"].shape == (6, 6)
    assert s["dforces_dmu"].shape == (9,)
    assert s["dmultipliers_dstate"].shape == (18, 21)
    assert s["multiplier_values"].shape == (18,)
    # Independent reference: central difference of two re-solves in mu,
    # h = 1e-4 mu (truncation O(h^2): 1.4e-9 measured at 1e-3 mu; solve
    # error 1e-14 x cond ~3e4 / h), forces to 1e-6 relative.
    h = 1e-4 * 0.5
    f = [np.concatenate([c["force_world"] for c in quasiroll.solve(
        scene("paper"), "newton", mu=0.5 + d, nlp_tol=1e-14)["contacts"]])
        for d in (h, -h)]
    fd = (f[0] - f[1]) / (2 * h)
    assert np.max(np.abs(s["dforces_dmu"] - fd)) <= 1e-6 * np.max(np.abs(fd))
    # The CLI prints the same numbers (newton: the same bits).
    c = cli_json("solve", "--scene", os.path.join(SCENES, "paper.yaml"),
                 "--nlp", "newton", "--sensitivities")
    np.testing.assert_array_equal(np.array(c["sensitivities"]["dtwist_dstate"]),
                                  s["dtwist_dstate"])
    # A failed solve has no sensitivities; without the keyword, no key.
    assert quasiroll.solve(scene("incline10"), "newton", mu=0.1,
                           sensitivities=True)["sensitivities"] is None
    assert "sensitivities" not in quasiroll.solve(scene("paper"), "newton")


def test_step_derivative_matches_resimulation_and_cli():
    # step(): one interval and its derivative (docs/python.md, model.md
    # §7.9), numpy arrays named as the CLI's step_sensitivities keys.
    inc = scene("incline10")
    r = quasiroll.step(inc, dt=0.05, nlp="newton")
    assert r["status"] == "OK" and not r["one_sided"]
    assert r["method"] == "rk4-chain-rule+ift-kkt+central-fd"
    assert r["state_names"][2] == "x_g1" and r["rate_names"][1] == "alpha1"
    assert r["dstate_next_dstate"].shape == (21, 21)
    assert r["dstate_next_dmu"].shape == (21,)
    assert r["dstate_next_deps"].shape == (21,)
    assert r["dstate_next_drates"].shape == (21, 6)
    # Independent reference: central differences of re-simulated intervals
    # (value-only steps) in x_g1 and in mu, h = 1e-5 (pvc is
    # smooth there: truncation ~h^2, re-solve noise ~1e-15 / h; the C++
    # test measures 3e-9), to 1e-6 relative.
    h = 1e-5
    x = [quasiroll.step(inc, state=r["state"] + d * np.eye(21)[2], dt=0.05,
                        nlp="newton", derivatives=False)["state_next"]
         for d in (h, -h)]
    fd = (x[0] - x[1]) / (2 * h)
    col = r["dstate_next_dstate"][:, 2]
    assert np.max(np.abs(col - fd)) <= 1e-6 * np.max(np.abs(fd))
    # mu (relative to max(|fd|, dt), as the C++ test).
    m = [quasiroll.step(inc, dt=0.05, nlp="newton", mu=0.5 + d,
                        derivatives=False)["state_next"] for d in (h, -h)]
    fd = (m[0] - m[1]) / (2 * h)
    scale = max(np.max(np.abs(fd)), 0.05)
    assert np.max(np.abs(r["dstate_next_dmu"] - fd)) <= 1e-6 * scale
    # The CLI prints the same numbers (the same computation).
    c = cli_json("solve", "--scene", os.path.join(SCENES, "incline10.yaml"),
                 "--nlp", "newton", "--step-derivative", "--dt", "0.05")
    cs = c["step_sensitivities"]
    np.testing.assert_array_equal(np.array(cs["dstate_next_dstate"]),
                                  r["dstate_next_dstate"])
    np.testing.assert_array_equal(np.array(cs["state_next"]), r["state_next"])
    # Without derivatives: the value, derivatives None; misuse: ValueError
    # naming the keyword.
    v = quasiroll.step(inc, dt=0.05, nlp="newton", derivatives=False)
    np.testing.assert_array_equal(v["state_next"], r["state_next"])
    assert v["dstate_next_dstate"] is None
    with pytest.raises(ValueError, match="state: must have 21"):
        quasiroll.step(inc, state=[0.0, 1.0])
    with pytest.raises(ValueError, match="dae: must be"):
        quasiroll.step(inc, dae="no-such-integrator")
    with pytest.raises(ValueError, match="dt"):
        quasiroll.step(inc, dt=-1.0)


@pytest.mark.skipif(not BIN, reason="QUASIROLL_BINARY not set")
def test_failed_solve_has_none_not_zeros_and_equals_cli():
    # 10 degree incline, pvc: rolling needs mu > 0.318914 (docs/model.md).
    r = quasiroll.solve(scene("incline10"), "newton", mu=0.1)
    assert r["status"] == "INFEASIBLE_FRICTION" and not r["ok"]
    assert r["twist"] is None and r["joint_rates"] is None
    assert r["contacts"] is None and r["gap"] is None
    assert r["critical_wheel"] == 2
    assert abs(r["mu_min"] - 0.318914) < 1e-6
    c = cli_json("solve", "--scene", os.path.join(SCENES, "incline10.yaml"),
                 "--mu", "0.1")
    assert c["critical_wheel"] == r["critical_wheel"]
    assert c["mu_min"] == r["mu_min"]


@pytest.mark.skipif(not BIN, reason="QUASIROLL_BINARY not set")
def test_solve_iteration_limit_and_options_equal_cli():
    # The solve takes a run's quasi-static keys (nlp_max_iter, nlp_options)
    # with the same rules and effect as `quasiroll solve`'s flags.
    paper = os.path.join(SCENES, "paper.yaml")
    full = quasiroll.solve(scene("paper"), "newton")
    assert full["ok"] and full["iterations"] > 1
    capped = quasiroll.solve(scene("paper"), "newton", nlp_max_iter=1)
    c = cli_json("solve", "--scene", paper, "--nlp", "newton",
                 "--nlp-max-iter", "1")
    assert capped["status"] == c["status"]
    assert capped["iterations"] == c["iterations"] < full["iterations"]
    # newton (dense LU) gives the same bits in both processes.
    r = quasiroll.solve(scene("paper"), "newton",
                        nlp_options={"polish_floor": 1e-13})
    c = cli_json("solve", "--scene", paper, "--nlp", "newton",
                 "--nlp-opt", "polish_floor=1e-13")
    assert r["status"] == c["status"] == "OK"
    np.testing.assert_array_equal(r["twist"], c["twist"])
    with pytest.raises(ValueError, match="nlp_max_iter"):
        quasiroll.solve(scene("paper"), nlp_max_iter=0)
    with pytest.raises(ValueError, match="no_such_option"):
        quasiroll.solve(scene("paper"), "ipopt",
                        nlp_options={"no_such_option": 1})


@pytest.mark.skipif(not BIN, reason="QUASIROLL_BINARY not set")
def test_run_equals_cli_run(tmp_path):
    traj, stats = quasiroll.run(scene("paper"), "newton", "rk-baumgarte",
                                t_end=2, sigma=2.0, rk_method="rk4")
    subprocess.run([BIN, "run", "--scene", os.path.join(SCENES, "paper.yaml"),
                    "--dae", "rk-baumgarte", "--t-end", "2", "--sigma", "2",
                    "--rk-method", "rk4", "--out", str(tmp_path)],
                   check=True, capture_output=True)
    with open(tmp_path / "trajectory.csv") as f:
        rows = list(csv.reader(f))
    assert list(traj.columns) == rows[0]
    assert len(traj) == len(rows) - 1 == stats["samples"] == 41
    for j, name in enumerate(rows[0]):
        if name == "nlp_status":
            assert list(traj[name]) == [r[j] for r in rows[1:]]
        else:  # the same 17 significant digits, bit for bit
            np.testing.assert_array_equal(
                traj[name].to_numpy(), [float(r[j]) for r in rows[1:]])
    cli = json.load(open(tmp_path / "run.json"))
    assert stats["status"] == cli["status"] == "success"
    assert stats["counters"] == cli["counters"]
    assert stats["options"] == cli["options"]


def test_run_backend_options_equal_cli_flags(tmp_path):
    # A backend's own options through Python give what --nlp-opt/--dae-opt give.
    traj, stats = quasiroll.run(scene("paper"), "ipopt", "rk-projection", t_end=1,
                                nlp_options={"mu_strategy": "adaptive"},
                                dae_options={"rk_method": "rk4"})
    subprocess.run([BIN, "run", "--scene", os.path.join(SCENES, "paper.yaml"),
                    "--nlp", "ipopt", "--dae", "rk-projection", "--t-end", "1",
                    "--nlp-opt", "mu_strategy=adaptive", "--dae-opt", "rk_method=rk4",
                    "--out", str(tmp_path)], check=True, capture_output=True)
    cli = json.load(open(tmp_path / "run.json"))
    assert stats["options"] == cli["options"]
    assert "adaptive" in json.dumps(stats["options"])
    with open(tmp_path / "trajectory.csv") as f:
        assert len(traj) == len(list(csv.reader(f))) - 1
    with pytest.raises(ValueError, match="no_such_option"):
        quasiroll.run(scene("flat"), "ipopt", t_end=1,
                      nlp_options={"no_such_option": 1})
    with pytest.raises(ValueError, match="dae_options: must be a dict"):
        quasiroll.run(scene("flat"), t_end=1, dae_options="rk_method=rk4")


def test_run_event_settings_equal_cli_flags(tmp_path):
    # The located-stop settings are run settings like any other.
    _, stats = quasiroll.run(scene("paper"), t_end=1, locate_events=False,
                             event_points=5, event_tolerance=1e-6,
                             locate_switches=False)
    subprocess.run([BIN, "run", "--scene", os.path.join(SCENES, "paper.yaml"),
                    "--t-end", "1", "--locate-events", "false",
                    "--event-points", "5", "--event-tolerance", "1e-6",
                    "--locate-switches", "false",
                    "--out", str(tmp_path)], check=True, capture_output=True)
    cli = json.load(open(tmp_path / "run.json"))
    assert stats["options"] == cli["options"]
    events = stats["options"]["events"]
    assert events["locate"] is False
    assert events["points"] == 5 and events["tolerance"] == 1e-6
    with pytest.raises(ValueError, match="event_tolerance: must be"):
        quasiroll.run(scene("flat"), event_tolerance=0)


def test_run_arrays_and_keyword_errors():
    d, stats = quasiroll.run(scene("flat"), t_end=1, as_frame=False)
    # Flat straight drive: x = rho * alphadot * t = 0.1 * 0.6 * t
    # (docs/model.md, the flat oracle), to the integrator's rounding.
    np.testing.assert_allclose(d["x"], 0.06 * d["t"], atol=1e-12)
    assert d["nlp_status"][0] == "OK"
    assert stats["critical_wheel"] is None
    for kw, value, text in [("dt", 0, "dt: must be a finite number > 0"),
                            ("t_end", -1, "t_end: must be"),
                            ("sigma", -1, "sigma: must be a finite number >= 0"),
                            ("dae_index", 3, "dae_index: must be an integer"),
                            ("mode", "x", "mode: must be one of paper, pvc")]:
        with pytest.raises(ValueError, match=text):
            quasiroll.run(scene("flat"), **{kw: value})
    with pytest.raises(ValueError, match="nlp: must be one of"):
        quasiroll.run(scene("flat"), "nope")


def test_failed_run_reports_status_and_wheel():
    traj, stats = quasiroll.run(scene("incline10"), mu=0.1, t_end=1)
    assert stats["status"] == "INFEASIBLE_FRICTION"
    assert stats["critical_wheel"] == 2
    assert len(traj) == 1 and traj["nlp_status"][0] == "INFEASIBLE_FRICTION"


def test_run_releases_the_gil():
    # While a simulation runs in a worker thread, this thread must keep
    # running Python. Holding the GIL in C++ would stall it for the whole
    # simulation; the stalls longer than 50 ms must add up to less than half
    # of the simulation's own wall time (run.json wall_s, >= 0.2 s here).
    s = scene("paper")
    done = threading.Event()
    result = {}

    def work():  # 401 ipopt solves, ~1 ms each
        result["stats"] = quasiroll.run(s, "ipopt", as_frame=False)[1]
        done.set()

    worker = threading.Thread(target=work)
    last = time.perf_counter()
    stalled = 0.0
    worker.start()
    while not done.is_set():
        # Sleeping (not spinning) leaves the CPU to the worker; waking up
        # needs the GIL, so a held GIL shows as a long gap.
        time.sleep(0.002)
        now = time.perf_counter()
        if now - last > 0.05:
            stalled += now - last
        last = now
    worker.join()
    wall = result["stats"]["wall_s"]
    assert wall > 0.2, f"simulation too short to tell ({wall} s)"
    assert stalled < 0.5 * wall, (stalled, wall)


def test_ctrl_c_interrupts_a_run():
    code = ("import quasiroll, sys\n"
            f"s = quasiroll.load_scene({os.path.join(SCENES, 'flat.yaml')!r})\n"
            "print('started', flush=True)\n"
            "try:\n"
            "    quasiroll.run(s, t_end=20000)\n"  # ~10 s uninterrupted
            "except KeyboardInterrupt:\n"
            "    print('interrupted', flush=True)\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                         text=True, env=os.environ)
    assert p.stdout.readline().strip() == "started"
    time.sleep(0.5)
    p.send_signal(signal.SIGINT)
    try:
        out, _ = p.communicate(timeout=60)
    finally:
        p.kill()
    assert out.strip() == "interrupted"


@pytest.mark.skipif(not BIN, reason="QUASIROLL_BINARY not set")
def test_load_runs(tmp_path):
    suite = os.path.join(SRC, "tests", "data", "suites", "cli_contract.yaml")
    subprocess.run([BIN, "bench", "--suite", suite, "--out", str(tmp_path),
                    "--jobs", "1", "--progress", "none"], check=True,
                   capture_output=True)
    runs = quasiroll.load_runs(tmp_path)
    with open(tmp_path / "runs.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(runs.columns) == list(rows[0].keys())
    assert len(runs) == 2
    flat = runs[runs.scene == "flat"].iloc[0]
    low = runs[runs.scene == "incline_low_mu"].iloc[0]
    assert flat.status == "success" and low.status == "INFEASIBLE_FRICTION"
    assert np.isnan(flat.critical_wheel) and low.critical_wheel == 2
    assert runs.wall_s.dtype == float and runs.stop_reason.dtype == object
    assert flat.stop_reason == ""
    with pytest.raises(FileNotFoundError, match="runs.csv"):
        quasiroll.load_runs(tmp_path / "nowhere")


def test_worked_example_of_docs_python_md(tmp_path):
    # The first ```python block of docs/python.md, run as a user would from
    # the source directory; it must write its figure.
    text = open(os.path.join(SRC, "docs", "python.md"), encoding="utf-8").read()
    block = re.findall(r"```python\n(.*?)```", text, re.S)[0]
    block = block.replace('fig.savefig("paper_track.png"',
                          f'fig.savefig({str(tmp_path / "paper_track.png")!r}')
    out = subprocess.run([sys.executable, "-c", block], capture_output=True,
                         text=True, env=os.environ, cwd=SRC)
    assert out.returncode == 0, out.stderr
    assert "rk-projection success" in out.stdout, out.stdout
    png = (tmp_path / "paper_track.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10000


PLUGIN = os.environ.get("QUASIROLL_EXAMPLE_PLUGIN", "")


@pytest.mark.skipif(not PLUGIN, reason="QUASIROLL_EXAMPLE_PLUGIN not set")
def test_load_plugin_adds_backends_that_run():
    # A bad path: ValueError naming the file.
    with pytest.raises(ValueError, match="no such file"):
        quasiroll.load_plugin(PLUGIN + ".missing")
    info = quasiroll.load_plugin(PLUGIN)
    assert info["nlp"] == ["levenberg-marquardt"]
    assert info["dae"] == ["midpoint-projection"]
    assert len(info["sha256"]) == 64 and info["version"] == "0.1.0"
    assert "levenberg-marquardt" in quasiroll.backends()["nlp"]
    # Loading the same file again is a no-op returning the same record.
    assert quasiroll.load_plugin(PLUGIN) == info
    scene = quasiroll.load_scene(os.path.join(SRC, "bench/scenes/paper.yaml"))
    _, stats = quasiroll.run(scene, nlp="levenberg-marquardt",
                             dae="midpoint-projection", t_end=0.2)
    assert stats["status"] == "success", stats["stop_reason"]
