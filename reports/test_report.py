#!/usr/bin/python3
"""Tests of the report generator: /usr/bin/python3 reports/test_report.py

Builds a synthetic results directory (make_fixture.py) in a temp dir, runs
make_report.py on it as a subprocess and checks the page, the PNG/SVG files
and the bad-input behaviour. Last line printed: "N passed, N failed".
"""

import csv
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import types
import unittest
from html import escape

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
os.environ["MPLBACKEND"] = "Agg"

import make_fixture  # noqa: E402
from quasiroll_report import selection as sel  # noqa: E402
import numpy as np  # noqa: E402
from quasiroll_report import plotting  # noqa: E402
from quasiroll_report import robot  # noqa: E402
from quasiroll_report import problems  # noqa: E402
from quasiroll_report import data  # noqa: E402
from quasiroll_report import data as data_module  # noqa: E402
from quasiroll_report.data import read_meta, read_references, read_runs  # noqa: E402
from quasiroll_report.report import FIGURE_NAMES  # noqa: E402

# The fixture's stability groups: one chart (figure) each.
STABILITY_FIGURES = ["fig_stability_dt", "fig_stability_mu", "fig_stability_roughness",
                     "fig_stability_sigma_dt"]
DRAWN_FIGURES = [n for n in FIGURE_NAMES if n != "fig_stability"] + STABILITY_FIGURES

PYTHON = "/usr/bin/python3"
MAKE_REPORT = os.path.join(HERE, "make_report.py")
FAILED_ONLY = "ceres/rk-baumgarte/coupled"
# The fixture's σ = 30 run fails: an option variant, so a method of its own.
FAILED_VARIANT = "ipopt/rk-baumgarte[baumgarte_sigma=30]/zoh"
# The fixture's option variant of newton/rk-projection/zoh (make_fixture.py).
VARIANT = "newton/rk-projection[projection_tolerance=1e-08]/zoh"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run_report(results_dir, *extra):
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("QUASIROLL_REPORT_DEBUG", None)
    return subprocess.run([PYTHON, MAKE_REPORT, results_dir, *extra],
                          capture_output=True, text=True, env=env, timeout=300)


def png_size(path):
    """(width, height) from the IHDR chunk; raises if not a PNG."""
    with open(path, "rb") as handle:
        head = handle.read(33)
    if head[:8] != PNG_MAGIC or head[12:16] != b"IHDR":
        raise ValueError(f"{path} is not a PNG")
    return struct.unpack(">II", head[16:24])


def read_csv(path):
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    return rows[0], rows[1:]


def write_csv(path, header, rows):
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(header)
        writer.writerows(rows)


def edit_csv(path, edit):
    """Rewrites the CSV file at path as edit(header, rows) -> (header, rows)."""
    header, rows = read_csv(path)
    write_csv(path, *edit(header, rows))


def drop_column(name):
    """An edit_csv edit that removes column name."""
    def edit(header, rows):
        drop = header.index(name)
        return ([h for i, h in enumerate(header) if i != drop],
                [[v for i, v in enumerate(r) if i != drop] for r in rows])
    return edit


def set_column(name, value, first_only=False):
    """An edit_csv edit that sets column name to value (in the first row only
    with first_only)."""
    def edit(header, rows):
        for row in rows[:1] if first_only else rows:
            row[header.index(name)] = value
        return header, rows
    return edit


def infeasible_friction_cells(test):
    """The INFEASIBLE_FRICTION cells of test's dt stability chart (some)."""
    data = test.manifest()["fig_stability_dt"]["data"]
    cells = [c for p in data["panels"] for c in p["cells"]
             if c["status"] == "INFEASIBLE_FRICTION"]
    test.assertTrue(cells)
    return cells


class Fixture:
    """One fixture + report shared by the tests, and copies to mutate."""
    root = None
    good = None
    result = None

    legacy = None
    legacy_result = None

    @classmethod
    def setup(cls):
        cls.root = tempfile.mkdtemp(prefix="quasiroll_report_test_")
        cls.good = make_fixture.build_fixture(os.path.join(cls.root, "good"), seed=7)
        cls.result = run_report(cls.good)
        cls.legacy = make_fixture.build_fixture(os.path.join(cls.root, "legacy"), seed=7,
                                                legacy=True)
        cls.legacy_result = run_report(cls.legacy)

    @classmethod
    def copy(cls, name):
        target = os.path.join(cls.root, name)
        shutil.copytree(cls.good, target, ignore=shutil.ignore_patterns("report"))
        return target

    @classmethod
    def teardown(cls):
        if cls.root:
            shutil.rmtree(cls.root, ignore_errors=True)


def setUpModule():
    Fixture.setup()


def tearDownModule():
    Fixture.teardown()


class GoodReportTest(unittest.TestCase):
    def setUp(self):
        self.result = Fixture.result
        self.report_dir = os.path.join(Fixture.good, "report")

    def html(self):
        with open(os.path.join(self.report_dir, "index.html"), encoding="utf-8") as handle:
            return handle.read()

    def manifest(self):
        with open(os.path.join(self.report_dir, "figures.json")) as handle:
            return {entry["name"]: entry for entry in json.load(handle)}

    def assert_html(self, has=(), lacks=()):
        """index.html contains every text of has and none of lacks."""
        html = self.html()
        for text in has:
            self.assertIn(text, html)
        for text in lacks:
            self.assertNotIn(text, html)

    def test_exit_code_and_last_line_is_index_path(self):
        self.assertEqual(self.result.returncode, 0, self.result.stderr)
        last = self.result.stdout.strip().splitlines()[-1]
        self.assertEqual(last, os.path.abspath(os.path.join(self.report_dir, "index.html")))
        self.assertTrue(os.path.isabs(last))
        self.assertNotIn("Traceback", self.result.stderr)

    def test_index_references_every_figure(self):
        html = self.html()
        for name in DRAWN_FIGURES:
            self.assertIn(f'src="{name}.png"', html, name)
            self.assertIn(f'href="{name}.svg"', html, name)
        self.assertNotIn("<script", html.lower())

    def test_pngs_are_valid_with_expected_size(self):
        import matplotlib.image
        manifest = self.manifest()
        self.assertEqual(sorted(manifest), sorted(DRAWN_FIGURES))
        for name, entry in manifest.items():
            path = os.path.join(self.report_dir, f"{name}.png")
            self.assertGreater(os.path.getsize(path), 5000, name)
            width, height = png_size(path)
            want_w = entry["figsize_in"][0] * entry["dpi"]
            want_h = entry["figsize_in"][1] * entry["dpi"]
            self.assertLessEqual(abs(width - want_w), 3, name)
            self.assertLessEqual(abs(height - want_h), 3, name)
            pixels = matplotlib.image.imread(path)
            self.assertGreater(float(pixels[..., :3].std()), 0.02, f"{name} looks blank")

    def test_fixed_figure_sizes(self):
        manifest = self.manifest()
        width, height = png_size(os.path.join(self.report_dir, "fig_work_precision.png"))
        self.assertLessEqual(abs(width - 1300), 2)   # 13 in x (0.6 + 3.9 per problem)
        self.assertLessEqual(abs(height - 840), 2)   # two problems
        self.assertEqual(manifest["fig09_normal_forces"]["figsize_in"], [8.0, 4.2])

    def test_svgs_exist(self):
        for name in DRAWN_FIGURES:
            path = os.path.join(self.report_dir, f"{name}.svg")
            self.assertTrue(os.path.isfile(path), name)
            with open(path, encoding="utf-8") as handle:
                self.assertIn("<svg", handle.read(2000), name)

    def test_summary_lists_failed_only_method(self):
        html = self.html()
        summary = html.split("<h2>Summary per method</h2>")[1].split("<h2>")[0]
        self.assertIn(FAILED_ONLY, summary)
        self.assertIn("all runs failed", summary)
        self.assertIn("SOLVER_FAILURE", summary)

    def test_force_figures_mark_the_located_switches(self):
        manifest = self.manifest()
        for name in ("fig09_normal_forces", "fig10_longitudinal_traction",
                     "fig11_lateral_traction"):
            caption = manifest[name]["caption"]
            self.assertIn("the 2 stick/slide switches of this run (2 located", caption)
            self.assertIn("(wheel 1 stick→slide)", caption)
            self.assertIn("(wheel 3 slide→stick)", caption)
            # The creep reversal apart from the switches (docs/model.md §8.6).
            self.assertIn("Dash-dotted: the 1 creep reversal(s)", caption)
            self.assertIn("(wheel 3).", caption)
            # The solution jump: one time for its three wheels' events.
            self.assertIn("Dashed black: 1 solution jump(s)", caption)

    def test_force_figures_say_when_switch_times_are_missing(self):
        with open(os.path.join(Fixture.legacy, "report", "figures.json")) as handle:
            manifest = {entry["name"]: entry for entry in json.load(handle)}
        self.assertIn("switch times are not in the results",
                      manifest["fig09_normal_forces"]["caption"])

    def test_failed_only_method_noted_in_accuracy_caption(self):
        html = self.html()
        block = html.split('id="fig_work_precision"')[1].split("</figure>")[0]
        self.assertIn("Omitted because all their runs failed: " + FAILED_ONLY, block)

    def test_metadata_and_failure_table(self):
        html = self.html()
        for text in ("0123abc (fixture)", "fixture-host", "ipopt 3.14.10",
                     "blas: /fixture/blas/libblas.so.3",
                     "2024-01-01T00:05:00Z", "INFEASIBLE_FRICTION", "μ_min"):
            self.assertIn(text, html)
        self.assertIn('<table class="map">', html)

    # ---- issue #14: like with like

    def test_work_precision_facets_never_mix_problems(self):
        panels = self.manifest()["fig_work_precision"]["data"]["panels"]
        # two problems (8 s zoh ladder, 2 s coupled ladder) x two metrics
        self.assertEqual(len(panels), 4)
        self.assertEqual(sorted({tuple(p["t_end"]) for p in panels}),
                         [(make_fixture.T_END_CPL,), (make_fixture.T_END,)])
        runs = read_runs(Fixture.good)[0]
        for panel in panels:
            self.assertEqual(len(panel["t_end"]), 1, panel["problem"])
            self.assertEqual(len(panel["ref_hashes"]), 1, panel["problem"])
            # every point of the Pareto front is a run of this panel's problem
            mine = [r for r in runs if r["ref_hash"] == panel["ref_hashes"][0]
                    and r["status"] == "success"]
            errs = {round(r[panel["metric"]], 15) for r in mine}
            for err, _ in panel["front"]:
                self.assertIn(round(err, 15), errs, panel["problem"])
        cpl = [p for p in panels if p["t_end"] == [make_fixture.T_END_CPL]]
        self.assertTrue(all(line.endswith("/coupled") for p in cpl for line in p["lines"]))

    def test_recommendation_table_closes_the_report(self):
        html = self.html()
        self.assertEqual(html.count('<h3 class="recommendation">'), 2, "one per problem")
        self.assertGreater(html.index('id="recommendation"'), html.index('id="reproduction"'))
        self.assertIn("Timed on ", html)
        runs = read_runs(Fixture.good)[0]
        for problem, floor, recs in sel.recommendation_tables(runs):
            reached = [r for r in recs if r["winner"] is not None]
            self.assertTrue(reached, problem["label"])
            for rec in reached:
                # the winner reaches E and nothing of its problem reaching E is faster
                self.assertLessEqual(rec["winner"]["err"], rec["target"])
                faster = [r for r in problem["rows"] if r["err_pos_rms"] <= rec["target"]
                          and sel.timing(r)[0] < rec["winner"]["wall"]]
                self.assertEqual(faster, [], rec["target"])

    def test_work_precision_points_labelled(self):
        panels = self.manifest()["fig_work_precision"]["data"]["panels"]
        runs = sel.work_precision_rows(read_runs(Fixture.good)[0])
        for panel in panels:
            for line, labels in panel["labels"].items():
                dts = sorted({r["dt"] for r in runs if r["method"] == line
                              and r[panel["metric"]] > 0
                              and r["ref_hash"] == panel["ref_hashes"][0]
                              and r["status"] == "success"}, reverse=True)
                self.assertEqual(labels, [f"{dt:g}" for dt in dts], line)

    def test_bands_table_per_problem(self):
        runs = read_runs(Fixture.good)[0]
        bands = sel.accuracy_bands(runs)
        self.assertEqual(len(bands), 2)
        for problem, rows in bands:
            self.assertTrue(rows)
            for _, fastest, _ in rows:
                self.assertEqual(fastest["t_end"], problem["t_end"])
                self.assertEqual(fastest["ref_hash"], problem["ref_hash"])
        html = self.html()
        self.assertEqual(html.count("<h3>paper · "), 2, "one bands table per problem")

    def test_timing_median_with_error_bars(self):
        data = self.manifest()["fig_work_precision"]["data"]
        self.assertEqual(data["timing"], "median")
        caption = self.manifest()["fig_work_precision"]["caption"]
        self.assertIn("median wall time over the repeats", caption)
        runs = read_runs(Fixture.good)[0]
        run = next(r for r in runs if r["status"] == "success")
        point, low, high = sel.timing(run)
        self.assertEqual(point, run["wall_s_median"])
        self.assertLess(low, point)
        self.assertGreater(high, point)

    def test_mu_sweep_per_mode_not_pooled(self):
        for name in ("fig13_traction_vs_mu", "fig14_total_slip_vs_mu"):
            panels = self.manifest()[name]["data"]["panels"]
            self.assertEqual([p["scene"] for p in panels], ["paper", "paper_pvc"], name)
            # μ_min per scene from ref_mu_min, not from the stop values (0.25)
            self.assertAlmostEqual(panels[0]["mu_min"], make_fixture.REF_MU_MIN["paper"])
            self.assertAlmostEqual(panels[1]["mu_min"], make_fixture.REF_MU_MIN["paper_pvc"])
        slip = self.manifest()["fig14_total_slip_vs_mu"]["data"]
        # pooled curves would average the two modes; per mode the fixture's
        # 1000x slip difference must survive
        ratio = slip["per_scene"]["paper"] / slip["per_scene"]["paper_pvc"]
        self.assertGreater(ratio, 100)
        pvc = slip["panels"][1]["curves"]
        for curve in pvc.values():
            self.assertTrue(all(mu > make_fixture.REF_MU_MIN["paper_pvc"] for mu, _ in curve))
        # Sliding and creep apart (issue #21 item 4): pvc is stated as creep,
        # never as a slip ratio against paper mode's sliding.
        self.assert_html(
            has=["paper_pvc no sliding; creep", "proportional to ε", "paper slides"],
            lacks=["less than paper", "paper_pvc slips"])

    def test_slip_vs_mu_draws_sliding_and_creep_apart(self):
        # A referee's question: is the regularisation shown as physics? The
        # method-coloured curves are the sliding (runs.csv sliding_distance);
        # the creep (proportional to ε) is grey, and a panel without sliding
        # says so instead of drawing its creep in a method's colour.
        record = self.manifest()["fig14_total_slip_vs_mu"]
        figure = record["data"]
        self.assertTrue(figure["split"])
        runs = read_runs(Fixture.good)[0]
        by_scene = {p["scene"]: p for p in figure["panels"]}
        self.assertTrue(by_scene["paper"]["slides"])
        self.assertFalse(by_scene["paper_pvc"]["slides"])
        for scene, panel in by_scene.items():
            for method, curve in panel["curves"].items():
                for mu, value in curve:
                    rows = [r for r in sel.mu_sweep_rows(runs)
                            if r["scene"] == scene and r["mu"] == mu
                            and r["method"] == method and data.is_success(r)
                            and os.path.isfile(data.trajectory_path(Fixture.good, r))]
                    self.assertAlmostEqual(
                        value, float(np.median([r["sliding_distance"] for r in rows])),
                        delta=1e-12 * max(value, 1e-300))
                    creep = dict(panel["creep_curves"][method])[mu]
                    self.assertAlmostEqual(
                        creep, float(np.median([r["creep_distance"] for r in rows])),
                        delta=1e-12 * creep)
        self.assertIn("drawn apart", record["caption"])
        self.assertIn("grey, thin: the friction regularisation", record["caption"])

    def test_force_figures_say_lines_join_the_samples(self):
        for name in ("fig09_normal_forces", "fig10_longitudinal_traction",
                     "fig11_lateral_traction"):
            caption = self.manifest()[name]["caption"]
            self.assertIn("Lines join the output samples (Δt = 0.05 s)", caption, name)

    def test_slip_figure_marks_the_creep_band(self):
        # Creep (below 10 eps) is the regularisation, not motion: Fig. 12
        # shades it and says so (docs/model.md §7.5).
        caption = self.manifest()["fig12_slip"]["caption"]
        self.assertIn("Below 10 ε = 1.00e-07 m/s a wheel creeps", caption)
        self.assertIn("proportional to ε", caption)
        # The fixture's solution jump: where the slips jump (model.md §8.6).
        self.assertIn("Dashed black: 1 solution jump(s)", caption)

    def test_total_slip_is_the_runs_located_integral(self):
        # Fig. 14's points are runs.csv sliding_distance + creep_distance (the
        # harness's integrals with switches located: independent of the output
        # grid and equal to what the caption's regime text quotes), not the
        # trapezoid over the trajectory rows.
        runs, _ = read_runs(Fixture.good)
        slip = self.manifest()["fig14_total_slip_vs_mu"]["data"]
        mu = slip["compare_mu"]
        for scene, value in slip["per_scene"].items():
            located = [r["sliding_distance"] + r["creep_distance"]
                       for r in sel.mu_sweep_rows(runs)
                       if r["scene"] == scene and r["mu"] == mu and data.is_success(r)
                       and os.path.isfile(data.trajectory_path(Fixture.good, r))]
            self.assertTrue(located, scene)
            self.assertAlmostEqual(value, float(np.median(located)),
                                   delta=1e-12 * value, msg=scene)

    def test_blowup_is_numerical_not_friction_limit(self):
        cells = infeasible_friction_cells(self)
        for cell in cells:
            self.assertEqual(cell["cls"], "numerical", cell)
            self.assertEqual(cell["detail"], "drift_blowup", cell)
            self.assertIn(cell["colour"], plotting.NUMERICAL_COLOURS.values())
            self.assertNotIn(cell["colour"], plotting.PHYSICAL_COLOURS.values())
        mu = self.manifest()["fig_stability_mu"]["data"]
        physical = [c for p in mu["panels"] for c in p["cells"] if c["cls"] == "physical"]
        self.assertTrue(physical)
        self.assertTrue(all(c["colour"] == plotting.PHYSICAL_COLOURS["friction_limit"]
                            for c in physical))

    def test_stability_charts_only_methods_that_ran(self):
        data = self.manifest()["fig_stability_sigma_dt"]["data"]
        self.assertEqual([p["rows"] for p in data["panels"]],
                         [["ipopt/rk-baumgarte/zoh"]])
        for panel in data["panels"]:
            labels = [c["label"] for c in panel["cells"]]
            self.assertIn("1", labels)
            self.assertTrue(any(label.startswith(".") for label in labels), labels)

    def test_drift_figure_shows_the_drift_within_the_steps(self):
        entry = self.manifest()["fig_drift"]
        self.assertTrue(entry["data"]["step_drift"])
        # The drift-over-time legend sits in a band of its own.
        self.assertEqual(entry["data"]["points_under_legend"], 0)
        self.assertIn("Bottom row: drift_step_max", entry["caption"])
        # The fixture's zoh rk-projection removes 5.6e-4 dt^2 per interval
        # while its samples sit at ~1e-13: the caption names both.
        runs = read_runs(Fixture.good)[0]
        rep = [r for r in runs if r["dae"] == "rk-projection" and r["coupling"] == "zoh"
               and r["status"] == "success"]
        self.assertTrue(rep)
        self.assertRegex(entry["caption"], r"rk-projection max [0-9.e-]+, within its steps")

    def test_references_findings_validity_and_repro(self):
        self.assert_html(
            has=['id="findings"', "For RMS position error ≤", "References</h2>",
                 "estimated error", "Quasi-static validity", "quasi-static valid",
                 "matplotlib"],
            lacks=["Mixed hosts"])
        self.assertTrue(os.path.isfile(os.path.join(self.report_dir, "repro", "fixture.yaml")))
        self.assertTrue(os.path.isfile(os.path.join(self.report_dir, "repro", "scenes",
                                                    "paper.yaml")))


class RobotAndReplayTest(unittest.TestCase):
    GEOM = {"a": 0.25, "b": 0.25, "track": 0.4, "z_h": 0.05, "R": 0.08, "r": 0.02,
            "e": 0.0}

    def pose(self, **joints):
        row = {"x": 0.0, "y": 0.0, "z": 0.15, "roll": 0.0, "pitch": 0.0, "yaw": 0.0}
        row.update({name: 0.0 for name in robot.JOINTS})
        row.update(joints)
        return row

    def test_level_robot_touches_flat_ground_under_each_mount(self):
        # docs/model.md §1: on a plane the COM is z_h + R + r above the ground
        # and each wheel's lowest point is under its mount.
        geom, row = self.GEOM, self.pose()
        frames = robot.wheel_frames_world(geom, row)
        for (rot, centre), mount in zip(frames, robot.mount_points(geom)):
            contact = [mount[0], mount[1], 0.0]
            self.assertLess(robot.torus_residual(geom, rot, centre, contact), 1e-12)
            self.assertAlmostEqual(float(np.linalg.det(rot)), 1.0, places=12)
            # spin axis along the platform's y axis
            self.assertAlmostEqual(abs(float(rot[1, 2])), 1.0, places=12)

    def test_camber_tilts_the_rear_wheel_about_x(self):
        row = self.pose(delta2=0.3)
        rot, _ = robot.wheel_frames_world(self.GEOM, row)[1]
        axis = rot[:, 2]
        self.assertAlmostEqual(float(np.degrees(np.arccos(abs(axis[1])))), np.degrees(0.3),
                               places=9)
        self.assertAlmostEqual(float(axis[0]), 0.0, places=12)

    def test_replay_written_with_three_js(self):
        folder = os.path.join(Fixture.good, "report", "replay")
        if not os.path.isfile("/usr/share/javascript/three/three.min.js"):
            self.skipTest("libjs-three not installed")
        for name in ("index.html", "three.min.js", "OrbitControls.js", "data.js"):
            self.assertTrue(os.path.isfile(os.path.join(folder, name)), name)
        with open(os.path.join(folder, "data.js"), encoding="utf-8") as handle:
            text = handle.read()
        data = json.loads(text[text.index("=") + 1:].rstrip().rstrip(";"))
        self.assertEqual([d["scene"] for d in data], ["paper", "paper_pvc"])
        frame = data[0]["frames"][0]
        self.assertEqual(len(frame["wheels"]), 3)
        self.assertEqual(len(frame["platform"]), 12)
        normal = sum(frame["forces"][i][2] for i in range(3))
        self.assertGreater(normal, 0.5 * make_fixture.MASS * make_fixture.G)
        with open(os.path.join(Fixture.good, "report", "index.html"), encoding="utf-8") as f:
            self.assertIn('<iframe src="replay/index.html"', f.read())


class LegacyResultsTest(unittest.TestCase):
    """Results written before the issue-#14 columns existed."""

    def manifest(self):
        with open(os.path.join(Fixture.legacy, "report", "figures.json")) as handle:
            return {entry["name"]: entry for entry in json.load(handle)}

    def test_report_works_and_says_what_is_missing(self):
        result = Fixture.legacy_result
        self.assertEqual(result.returncode, 0, result.stderr)
        with open(os.path.join(Fixture.legacy, "report", "index.html"), encoding="utf-8") as f:
            html = f.read()
        for column in ("cause", "wall_s_median", "ref_err_est", "ref_mu_min"):
            self.assertIn(f"no <code>{column}</code> column", html)
        self.assertEqual(self.manifest()["fig_work_precision"]["data"]["timing"], "min")

    def test_legacy_drift_figure_says_step_drift_is_missing(self):
        entry = self.manifest()["fig_drift"]
        self.assertFalse(entry["data"]["step_drift"])
        self.assertIn("predate drift_step_max", entry["caption"])

    def test_legacy_blowup_is_unclassified_not_friction(self):
        cells = infeasible_friction_cells(self)
        for cell in cells:
            self.assertEqual(cell["cls"], "unknown")
            self.assertEqual(cell["colour"], plotting.UNKNOWN_COLOUR)
        self.assertIn("do not read them as physical limits",
                      self.manifest()["fig_stability_dt"]["caption"])

    def test_legacy_strict_still_passes(self):
        result = run_report(Fixture.legacy, "--strict", "--out",
                            os.path.join(Fixture.root, "legacy_strict"))
        self.assertEqual(result.returncode, 0, result.stderr)

    def test_legacy_mu_min_not_from_stops(self):
        panels = self.manifest()["fig14_total_slip_vs_mu"]["data"]["panels"]
        for panel in panels:
            self.assertTrue(panel["mu_min"] != panel["mu_min"], "nan without ref_mu_min")


class SelectionTest(unittest.TestCase):
    def runs(self):
        # Styles follow the build's backend list (meta.json "backends").
        problems.use_backends(read_meta(Fixture.good))
        return read_runs(Fixture.good)[0]

    def test_failed_only_method_not_in_work_precision_data(self):
        runs = self.runs()
        self.assertEqual(sel.failed_only_methods(runs), [FAILED_ONLY, FAILED_VARIANT])
        self.assertIn(FAILED_ONLY, [row["method"] for row in sel.method_summary(runs)])
        problems = sel.work_precision_problems(runs)
        self.assertEqual([p["t_end"] for p in problems],
                         [make_fixture.T_END, make_fixture.T_END_CPL])
        for metric in ("err_pos_rms", "err_force_rms"):
            series = sel.work_precision_series(runs, metric, rows=problems[0]["rows"])
            self.assertNotIn(FAILED_ONLY, series)
            self.assertEqual(len(series), 4)  # three pairs and a variant
            for points in series.values():
                self.assertEqual(len(points), 3)

    def test_work_precision_rows_only_work_precision_group(self):
        rows = sel.work_precision_rows(self.runs())
        self.assertTrue(rows)
        self.assertEqual({r["suite_group"] for r in rows},
                         {"work_precision", "work_precision_cpl"})
        self.assertTrue(all(r["status"] == "success" for r in rows))

    def test_pareto_front(self):
        points = [(1e-3, 1.0), (1e-4, 2.0), (1e-3, 0.5), (1e-2, 0.6), (1e-5, 10.0)]
        self.assertEqual(sel.pareto_front(points), [(1e-5, 10.0), (1e-4, 2.0), (1e-3, 0.5)])

    def test_method_styles_unique_and_stable(self):
        runs = self.runs()
        styles = sel.method_styles(runs)
        self.assertEqual(list(styles), sorted(styles))
        self.assertEqual(len(set(styles.values())), len(styles))
        self.assertEqual(styles, sel.method_styles(list(reversed(runs))))
        # colour per NLP, marker per integrator, whatever else is in the report
        self.assertEqual(styles["newton/rk-projection/zoh"][:2],
                         sel.method_styles(runs[-3:] + [dict(runs[0], method=
                                           "newton/rk-projection/zoh")])
                         ["newton/rk-projection/zoh"][:2])
        self.assertEqual(styles["newton/rk-projection/zoh"][0],
                         styles["newton/rk-projection/coupled"][0])
        self.assertNotEqual(styles["newton/rk-projection/zoh"][2],
                            styles["newton/rk-projection/coupled"][2])

    def test_stability_mu_line_from_reference(self):
        charts = {c["group"]: c for c in sel.stability_charts(self.runs(),
                                                              read_references(Fixture.good))}
        panels = {p["scene"]: p for p in charts["stability_mu"]["panels"]}
        self.assertAlmostEqual(panels["paper"]["mu_min"], 0.27)
        self.assertAlmostEqual(panels["paper_pvc"]["mu_min"], 0.43)
        self.assertEqual(sel.value_position([0.1, 0.3, 0.5], 0.4), 1.5)

    def test_epsilon_ladder_reads_sliding_and_creep_apart(self):
        # Issue #21 item 4, on made-up rows: pvc creeps in proportion to ε and
        # never slides; paper mode's sliding converges.
        from quasiroll_report import findings
        base = dict(self.runs()[0], suite_group="epsilon", status="success",
                    cause="", cause_detail="")
        rows = []
        for eps, slide in ((1e-7, 1.024e-3), (1e-8, 1.0672e-3), (1e-9, 1.0680e-3)):
            rows.append(dict(base, scene="paper", eps=eps, sliding_distance=slide,
                             creep_distance=60 * eps))
            rows.append(dict(base, scene="paper_pvc", eps=eps, sliding_distance=0.0,
                             creep_distance=25 * eps))
        paper, pvc = findings.epsilon_findings(rows)
        self.assertIn("sliding distance 0.001024, 0.0010672, 0.001068 m", paper)
        self.assertIn("no sliding at any ε", pvc)
        self.assertIn("creep/ε constant within 0", pvc)
        self.assertNotIn("sliding distance", pvc)
        self.assertNotIn("order ε²", paper)
        # Creep/ε drifting by more than 5 % where the scene slides: the
        # ε² tails of slides that slow to a stick are named (model.md §7.5).
        for r in rows:
            if r["scene"] == "paper":
                r["creep_distance"] = (56 + 2.7e9 * r["eps"]) * r["eps"]
        paper, _ = findings.epsilon_findings(rows)
        self.assertIn("creep/ε constant within 41 %", paper)
        self.assertIn("order ε²", paper)

    def test_validity_counts_failed_problems_not_blowups(self):
        # Issue #21 item 6: validity over every problem, failed runs up to
        # their stop included; a blow-up's motion is the method's, not counted.
        from quasiroll_report import findings
        base = dict(self.runs()[0], cause="", cause_detail="", status="success")
        ok = dict(base, run_id="a", qs_inertia_ratio=0.005)
        model = dict(base, run_id="b", status="INFEASIBLE_FRICTION", cause="model",
                     cause_detail="quasi_static_invalid", qs_inertia_ratio=0.15)
        blowup = dict(base, run_id="c", status="drift_exceeded", cause="numerical",
                      cause_detail="drift_blowup", qs_inertia_ratio=50.0)
        other = dict(base, run_id="d", ref_hash="another", status="SOLVER_FAILURE",
                     cause="numerical", cause_detail="solver_failure",
                     qs_inertia_ratio=0.001)
        rows = findings.qs_rows([ok, model, blowup, other], {})
        self.assertEqual(len(rows), 2)
        counted = {r[2]: r for r in rows}
        self.assertEqual(counted[2][3], 0.15)  # the failed run, not the blow-up
        self.assertTrue(np.isnan(counted[0][3]))  # named, with no measure
        text = findings.qs_findings([ok, model, blowup, other], {},
                                    {"qs_inertia_threshold": 0.01})[0]
        self.assertIn("1 of 1 measured problems exceed it", text)
        self.assertIn("1 without a measure", text)
        self.assertEqual(sel.failure_cause(model), ("model", "quasi_static_invalid"))
        self.assertEqual(plotting.cause_colour("model", "quasi_static_invalid"),
                         plotting.MODEL_COLOUR)
        # A chart cell: the model's limit ranks above a physical stop.
        physical = dict(model, cause="physical", cause_detail="friction_limit")
        self.assertEqual(sel.stability_cell([physical, model])["cls"], "model")
        # A run past a reference that failed numerically (reference_stop
        # reference_failure) is marked: its reach is not verified.
        past = dict(ok, reference_stop="reference_failure")
        cell = sel.stability_cell([past])
        self.assertTrue(cell["ref_failed"])
        self.assertTrue(cell["label"].endswith(sel.REFERENCE_FAILURE_MARK))
        plain = sel.stability_cell([dict(ok, reference_stop="physical:lift_off")])
        self.assertFalse(plain["ref_failed"])
        self.assertFalse(plain["label"].endswith(sel.REFERENCE_FAILURE_MARK))
        from quasiroll_report import html_page
        self.assertIn("<strong>reference failure</strong>",
                      html_page._reference_stop_cell({"reference_stop": "reference_failure"},
                                                     {}))
        self.assertEqual(html_page._reference_stop_cell(
            {"reference_stop": "end", "rescues": 2}, {}),
            "<td>end (2 intervals retried)</td>")

    def test_paper_run_is_most_accurate_at_mu_half(self):
        run = sel.paper_run(self.runs(), lambda r: True)
        self.assertEqual(run["scene"], "paper")
        self.assertAlmostEqual(run["mu"], 0.5)
        self.assertEqual(run["status"], "success")

    def test_drift_representatives_use_the_primary_runs_nlp(self):
        base = next(r for r in self.runs() if r["status"] == "success"
                    and r["scene"] == "paper" and r["coupling"] == "zoh")
        # The same integrator with two NLPs; the other NLP's run is finer.
        fine = dict(base, nlp="ceres", dt=base["dt"] / 2, run_id="a_fine")
        mine = dict(base, nlp="newton", run_id="b_mine")
        runs = [fine, mine]
        reps = sel.drift_representatives(runs, lambda r: True, mine)
        self.assertEqual(reps[base["dae"]]["run_id"], "b_mine")
        reps = sel.drift_representatives(runs, lambda r: True, fine)
        self.assertEqual(reps[base["dae"]]["run_id"], "a_fine")
        # Without a run of the primary's NLP: the finest run.
        reps = sel.drift_representatives([fine, dict(mine, nlp="slsqp")],
                                         lambda r: True, dict(mine, nlp="ipopt"))
        self.assertEqual(reps[base["dae"]]["run_id"], "a_fine")


class MethodIdentityTest(unittest.TestCase):
    """Issue #20: a method is what ran, its backend options included; option
    variants are never pooled with their pair."""

    def runs(self):
        problems.use_backends(read_meta(Fixture.good))
        return read_runs(Fixture.good)[0]

    def test_variant_is_its_own_line_not_pooled(self):
        runs = self.runs()
        self.assertIn(VARIANT, sel.method_names(runs))
        problem = sel.work_precision_problems(runs)[0]
        series = sel.work_precision_series(runs, "err_pos_rms", rows=problem["rows"])
        pair = data.method_base(VARIANT)
        self.assertEqual(len(series[VARIANT]), 3)
        self.assertEqual(len(series[pair]), 3)
        for point in series[VARIANT]:
            self.assertEqual(point["n"], 1)
            self.assertTrue(point["run"]["run_id"].startswith("wpv-"), point["run"]["run_id"])
        for point in series[pair]:
            self.assertEqual(point["n"], 1)
            self.assertFalse(point["run"]["run_id"].startswith("wpv-"))
        with open(os.path.join(Fixture.good, "report", "figures.json")) as handle:
            manifest = {entry["name"]: entry for entry in json.load(handle)}
        lines = manifest["fig_work_precision"]["data"]["panels"][0]["lines"]
        self.assertIn(VARIANT, lines)
        self.assertIn(pair, lines)

    def test_fastest_finding_names_the_variant(self):
        runs = self.runs()
        problem = sel.work_precision_problems(runs)[0]
        best = sel.fastest_within(problem["rows"], 1e-4)
        self.assertEqual(best["method"], VARIANT)
        with open(os.path.join(Fixture.good, "report", "index.html"), encoding="utf-8") as f:
            html = f.read()
        findings = html.split('id="findings"')[1].split("</ul>")[0]
        self.assertIn(f"the fastest method is {escape(VARIANT)} (", findings)
        # never credited to the pair under its plain name
        self.assertNotIn(f"the fastest method is {escape(data.method_base(VARIANT))} (",
                         findings)

    def test_variant_keeps_pair_colour_hollow_with_own_dashes(self):
        styles = sel.method_styles(self.runs())
        variant, pair = styles[VARIANT], styles[data.method_base(VARIANT)]
        self.assertEqual((variant.colour, variant.marker), (pair.colour, pair.marker))
        self.assertEqual(pair.facecolor, pair.colour)
        self.assertNotEqual(variant.facecolor, variant.colour)
        self.assertNotEqual(variant.linestyle, pair.linestyle)
        self.assertNotIn(variant.linestyle, problems.COUPLING_LINES.values())

    def test_method_ids_parse_and_derive(self):
        self.assertEqual(data.parse_method("a[x=1,y=2]/b[z=dp54]/coupled"),
                         ("a", [("x", "1"), ("y", "2")], "b", [("z", "dp54")], "coupled"))
        self.assertEqual(data.method_without("a/b[s=20,t=1]/zoh", {"s"}), "a/b[t=1]/zoh")
        self.assertEqual(data.method_base("a/b[s=20]/zoh"), "a/b/zoh")
        self.assertFalse(data.is_variant("a/b/zoh"))
        # Older runs.csv without `method`: from the shorthand columns.
        row = {"nlp": "a", "dae": "b", "coupling": "zoh", "rk_method": "dp54",
               "sigma": 20.0, "dae_index": 2.0}
        self.assertEqual(data.method_name(row), "a/b[baumgarte_sigma=20,rk_method=dp54]/zoh")
        # ... only the options the integrator has, when dae_options says so
        row["dae_options"] = '{"rk_method":"dp54","projection_tolerance":1e-12}'
        self.assertEqual(data.method_name(row), "a/b[rk_method=dp54]/zoh")
        row.update(rk_method="rk4", sigma=5.0)
        self.assertEqual(data.method_name(row), "a/b/zoh")
        self.assertEqual(data.method_name(dict(row, method="a[k=v]/b/zoh")), "a[k=v]/b/zoh")

    def test_legacy_runs_derive_the_sigma_variants(self):
        legacy = read_runs(Fixture.legacy)[0]
        self.assertIn(FAILED_VARIANT, sel.method_names(legacy))
        # the sigma axis is the chart's columns: its rows are the pairs
        charts = {c["group"]: c for c in sel.stability_charts(legacy)}
        self.assertEqual([p["rows"] for p in charts["stability_sigma_dt"]["panels"]],
                         [["ipopt/rk-baumgarte/zoh"]])


def _base_row(**fields):
    row = {"run_id": "r", "scene": "paper", "nlp": "n", "dae": "d", "coupling": "zoh",
           "method": "n/d/zoh", "dt": 0.1, "tol": 1e-6, "sigma": 5.0, "eps": 1e-8,
           "mu": 0.5, "seed": "1", "roughness": float("nan"), "t_end": 8.0,
           "status": "success", "t_reached": 8.0, "err_pos_rms": 1e-5, "substeps": 1.0}
    row.update(fields)
    return row


def _implicit_row(run_id, nlp, dae, options, wall, err, dt=0.2, tol=1e-8, **fields):
    """A successful coupled work-precision row of one problem; `options` the
    integrator's option table (dae_options), the non-default ones (DEFAULTS)
    also in the method id as the harness writes it."""
    defaults = {"jacobian": "ift", "lmm": "adams", "nonlinear_solver": "fixedpoint"}
    table = {"jacobian": "ift", **options}
    if dae == "cvode-projection":
        table = {"lmm": "adams", "nonlinear_solver": "fixedpoint", **table}
    listed = ",".join(f"{k}={v}" for k, v in sorted(table.items()) if defaults[k] != v)
    row = _base_row(run_id=run_id, suite_group="work_precision_cpl_implicit", nlp=nlp,
                    dae=dae, coupling="coupled", dt=dt, tol=tol, wall_s=wall,
                    err_pos_rms=err, t_end=20.0, ref_hash="problem-a",
                    method=f"{nlp}/{dae}" + (f"[{listed}]" if listed else "")
                    + "/coupled",
                    dae_options=json.dumps(table, sort_keys=True))
    row.update(fields)
    return row


class ImplicitFindingsTest(unittest.TestCase):
    """Coupled implicit integrators: exact (ift) vs finite-difference (fd)
    Jacobians and CVODE Adams vs BDF, on matched settings only."""
    BDF = {"lmm": "bdf", "nonlinear_solver": "newton"}

    @staticmethod
    def median(values):
        values = sorted(values)
        mid = len(values) // 2
        return values[mid] if len(values) % 2 else (values[mid - 1] + values[mid]) / 2

    def expected(self, ratios, note=""):
        return (f"{self.median(ratios):.2g}× ({min(ratios):.2g}–{max(ratios):.2g}× "
                f"over {len(ratios)} matched pairs{note})")

    def test_ratios_over_matched_pairs(self):
        from quasiroll_report import findings
        settings = [("newton", 0.2, 1.0), ("newton", 0.4, 2.0), ("slsqp", 0.2, 4.0),
                    ("slsqp", 0.4, 3.0)]
        ida_fd, ida_err = [2.0, 2.4, 3.0, 2.2], [0.001, 0.003, -0.002, 0.0005]
        bdf_fd, adams = [1.5, 1.2, 1.4, 1.1], [0.5, 0.6, 0.4, 0.7]
        adams_err = [0.05, 0.02, 0.04, 0.03]
        rows = []
        for k, (nlp, dt, wall) in enumerate(settings):
            rows += [
                _implicit_row(f"i{k}", nlp, "ida", {}, wall, 1e-6, dt),
                _implicit_row(f"f{k}", nlp, "ida", {"jacobian": "fd"}, wall * ida_fd[k],
                              1e-6 * (1 + ida_err[k]), dt),
                _implicit_row(f"b{k}", nlp, "cvode-projection", self.BDF, wall, 2e-7, dt),
                _implicit_row(f"g{k}", nlp, "cvode-projection",
                              dict(self.BDF, jacobian="fd"), wall * bdf_fd[k], 2e-7, dt),
                _implicit_row(f"a{k}", nlp, "cvode-projection", {}, wall * adams[k],
                              2e-7 * adams_err[k], dt)]
        # Not matched: an fd run at another tolerance, a failed exact run's
        # partner, a zoh pair; none may change the numbers.
        rows += [_implicit_row("x1", "newton", "ida", {"jacobian": "fd"}, 99.0, 1e-6,
                               tol=1e-6),
                 _implicit_row("x2", "ceres", "ida", {"jacobian": "fd"}, 99.0, 1e-6),
                 _implicit_row("x3", "ceres", "ida", {}, 1.0, 1e-6, status="SOLVER_FAILURE"),
                 _implicit_row("x4", "newton", "ida", {"jacobian": "fd"}, 99.0, 1e-6,
                               coupling="zoh", method="newton/ida[jacobian=fd]/zoh"),
                 _implicit_row("x5", "newton", "ida", {}, 1.0, 1e-6,
                               coupling="zoh", method="newton/ida/zoh")]
        jac, lmm = findings.implicit_findings(rows, {})
        self.assertTrue(jac.startswith("Coupled implicit integrators on paper"), jac)
        self.assertIn("finite-difference over exact (ift) Jacobians", jac)
        self.assertIn("ida " + self.expected(ida_fd, ", position errors differ by ≤ 0.3 %"), jac)
        self.assertIn("cvode-projection (BDF, Newton) "
                      + self.expected(bdf_fd, ", position errors differ by ≤ 0 %"), jac)
        self.assertIn("2.3× (2–3× over 4 matched pairs", jac)  # the numbers, by hand
        self.assertIn("cvode-projection (fixed-point vs Newton) takes "
                      + self.expected(adams) + " of BDF's wall time at "
                      + f"{self.median(adams_err):.2g}× its position error "
                      + f"({min(adams_err):.2g}–{max(adams_err):.2g}×)", lmm)
        self.assertTrue(lmm.startswith("Adams vs BDF (exact Jacobians) on paper"), lmm)
        # Wired into the page's key findings, after the work-precision ones.
        from types import SimpleNamespace
        ctx = SimpleNamespace(runs=rows, references={}, meta={})
        self.assertIn(jac, findings.key_findings(ctx, []))

    def test_unmatched_runs_give_no_sentence(self):
        from quasiroll_report import findings
        rows = [
            # ift and fd at different Δt; a failed fd run at the ift's Δt
            _implicit_row("i", "newton", "ida", {}, 1.0, 1e-6, dt=0.2),
            _implicit_row("f", "newton", "ida", {"jacobian": "fd"}, 2.0, 1e-6, dt=0.4),
            _implicit_row("g", "newton", "ida", {"jacobian": "fd"}, 2.0, 1e-6, dt=0.2,
                          status="step_size_too_small"),
            # different NLPs
            _implicit_row("b", "newton", "cvode-projection", self.BDF, 1.0, 1e-7),
            _implicit_row("c", "slsqp", "cvode-projection", dict(self.BDF, jacobian="fd"),
                          2.0, 1e-7),
            # Adams against a finite-difference BDF run only; at another tolerance
            _implicit_row("a", "slsqp", "cvode-projection", {}, 0.5, 1e-8),
            _implicit_row("d", "newton", "cvode-projection", {}, 0.5, 1e-8, tol=1e-6)]
        self.assertEqual(findings.implicit_findings(rows, {}), [])
        # The error column missing on one side: no pair either.
        rows[2]["status"] = "success"
        rows[2]["err_pos_rms"] = float("nan")
        self.assertEqual(findings.implicit_findings(rows, {}), [])
        # ... and with it, one pair and its sentence.
        rows[2]["err_pos_rms"] = 1e-6
        text, = findings.implicit_findings(rows, {})
        self.assertIn("ida 2× (1 matched pair, position errors differ by ≤ 0 %)", text)


class PaperFigureRefereeTest(unittest.TestCase):
    """The referee's points on the paper figures (figures_paper.py): Fig. 5's
    pair and camber labels, Fig. 6's draw order, the force and slip figures'
    breaks at located jumps, event styles and labels, the weight line, the
    tractions' internal forces and the μ_min horizon."""

    @staticmethod
    def traj(n=21, dt=0.1, **columns):
        """A trajectory of n samples: level pose, N_i = 49/3 N, slips 1e-5 m/s,
        the given columns."""
        traj = {name: np.zeros(n) for name in data.TRAJECTORY_COLUMNS}
        traj.update(t=np.arange(n) * dt, nlp_status=["OK"] * n)
        for i in (1, 2, 3):
            traj[f"n{i}"] = np.full(n, 49.0 / 3)
            traj[f"slip{i}"] = np.full(n, 1e-5)
        traj.update({k: np.asarray(v, dtype=float) for k, v in columns.items()})
        return traj

    @staticmethod
    def event(t, wheel, kind="switch", before="stick", after="slide"):
        return {"t": t, "wheel": wheel, "from": before, "to": after, "located": True,
                "kind": kind, "t_lower": t - 1e-9, "t_upper": t}

    @staticmethod
    def context(traj, events, references=None, terrain=None, **fields):
        run = _base_row(run_id="syn", ref_hash="h", **fields)
        store = types.SimpleNamespace(get=lambda r: traj, switches=lambda r: events,
                                      has=lambda r: True)
        return types.SimpleNamespace(primary=run, trajectories=store,
                                     references=references or {},
                                     terrain_of=lambda r: terrain, out_dir=None)

    @staticmethod
    def capture(function, ctx):
        """(figure, caption) of a figure function, not saved."""
        from quasiroll_report import figures_paper as fp
        captured = {}

        def keep(fig, out_dir, name, title, caption):
            captured.update(fig=fig, caption=caption)
            return types.SimpleNamespace(name=name, caption=caption, data={})
        original, fp.save_figure = fp.save_figure, keep
        try:
            function(ctx)
        finally:
            fp.save_figure = original
        return captured["fig"], captured["caption"]

    def manifest(self):
        with open(os.path.join(Fixture.good, "report", "figures.json")) as handle:
            return {entry["name"]: entry for entry in json.load(handle)}

    def fixture_context(self):
        from quasiroll_report.report import Context
        return Context(Fixture.good, os.path.join(Fixture.root, "paper_referee"))

    # 1. Fig. 5: a pair of equal t_end and Δt, the caption's claim checked
    def test_snapshot_pair_prefers_equal_horizon_and_step(self):
        primary = _base_row(run_id="p1", method="m1", t_end=20.0, t_reached=20.0, dt=0.025)
        runs = [primary,
                _base_row(run_id="q1", method="m1", scene="paper_pvc", t_end=6.0,
                          t_reached=6.0, dt=0.1),
                _base_row(run_id="p2", method="m2", t_end=20.0, t_reached=20.0, dt=0.05),
                _base_row(run_id="q2", method="m2", scene="paper_pvc", t_end=20.0,
                          t_reached=20.0, dt=0.05),
                # an ε twin pair, more accurate: the primary's ε wins
                _base_row(run_id="p3", method="m2", t_end=20.0, t_reached=20.0, dt=0.05,
                          eps=1e-7, err_pos_rms=1e-9),
                _base_row(run_id="q3", method="m2", scene="paper_pvc", t_end=20.0,
                          t_reached=20.0, dt=0.05, eps=1e-7)]
        paper, pvc = sel.snapshot_pair(runs, lambda r: True, "paper_pvc", primary)
        self.assertEqual((paper["run_id"], pvc["run_id"]), ("p2", "q2"))

    def test_fig5_says_differ_only_by_mode_only_when_true(self):
        from quasiroll_report import figures_paper as fp
        ctx = types.SimpleNamespace(references={}, terrain_of=lambda r: {"type": "plane"})
        paper = _base_row(run_id="p", method="m", t_end=20.0, dt=0.025)
        pvc = _base_row(run_id="q", method="m", scene="paper_pvc", t_end=6.0, dt=0.1)
        differences, compared = fp.pair_differences(ctx, paper, pvc)
        self.assertEqual(differences, ["t_end 20 s vs 6 s", "Δt 0.025 s vs 0.1 s"])
        text = fp._pair_sentence(paper, pvc, differences, compared)
        self.assertNotIn("differ only by", text)
        self.assertIn("t_end 20 s vs 6 s", text)
        twin = dict(paper, run_id="q", scene="paper_pvc")
        self.assertEqual(fp.pair_differences(ctx, paper, twin)[0], [])
        self.assertIn("differ only by the camber mode",
                      fp._pair_sentence(paper, twin, *fp.pair_differences(ctx, paper, twin)))
        # The fixture's pair: both scenes' μ = 0.5 runs of one method, 8 s, Δt 0.1.
        entry = self.manifest()["fig05_snapshots"]
        self.assertEqual(entry["data"]["differences"], [])
        self.assertIn("differ only by the camber mode", entry["caption"])

    def test_camber_labels_have_significant_digits_and_no_signed_zero(self):
        from quasiroll_report import figures_paper as fp
        self.assertEqual(fp.degrees_text(0.0), "0°")
        self.assertEqual(fp.degrees_text(-0.0), "0°")
        self.assertEqual(fp.degrees_text(0.0153), "+0.015°")
        self.assertEqual(fp.degrees_text(-0.00412), "-0.0041°")
        for panel in self.manifest()["fig05_snapshots"]["data"]["panels"]:
            for label in panel["camber_labels"]:
                self.assertNotRegex(label, r"[+-]0\.0°")
                self.assertRegex(label, r"^δ[23]=(0|[+-]\d\.?\d*(e-\d+)?)°$")

    # 2. lines break at located jumps, not at continuous switches
    def test_lines_break_at_located_jumps_only(self):
        from quasiroll_report import figures_paper as fp
        t = np.arange(21) * 0.1
        jumping = np.where(t > 1.05, 5.0, 0.0) + 0.01 * t
        smooth = 0.01 * t
        spans = fp._event_spans([self.event(1.05, 1)])
        self.assertEqual(fp.break_cuts(t, jumping, spans), [10])
        self.assertEqual(fp.break_cuts(t, smooth, spans), [])     # continuous: no break
        jump = fp._event_spans([self.event(0.55, w, "solution_jump", "slide", "slide")
                                for w in (1, 2, 3)])
        self.assertEqual(fp.break_cuts(t, smooth, jump), [5])     # a solution jump always
        xs, ys = fp.with_breaks(t, jumping, [10])
        self.assertEqual(xs.size, 22)
        self.assertTrue(np.isnan(ys[11]) and 1.0 < xs[11] < 1.1)
        # A stick window (slide→stick ... stick→slide) is a span of its own.
        window = fp._event_spans([self.event(0.92, 1, before="slide", after="stick"),
                                  self.event(1.08, 1)])
        self.assertIn((0.92 - 1e-9, 1.08, False), window)

    def test_extremes_leave_out_a_sample_inside_a_transition(self):
        from quasiroll_report import figures_paper as fp
        plotting.apply_style()
        lon = np.where(np.arange(21) * 0.1 > 1.05, 5.0, 0.0)
        lon[10] = 12.0                      # the sample at 1.0 s, mid-transition
        events = [self.event(0.92, 1, before="slide", after="stick"), self.event(1.08, 1)]
        ctx = self.context(self.traj(t1_lon=lon), events)
        fig, ax, facts = fp._wheel_figure(ctx, "t{i}_lon", "N")
        wheel1 = next(line for line in ax.get_lines() if line.get_label() == "wheel 1")
        self.assertEqual(int(np.sum(np.isnan(wheel1.get_ydata()))), 2)
        self.assertEqual(sorted(facts["inside"]), [1.0])
        text = fp._range_text(facts, ctx.primary, "N")
        self.assertIn("[0, 5] N", text)
        self.assertIn("leaving out 1 sample(s) that fall inside a transition", text)
        plotting.plt.close(fig)

    # 3. Fig. 12: located reversals marked, the dip explained
    def test_slip_figure_marks_located_reversals(self):
        from quasiroll_report import figures_paper as fp
        plotting.apply_style()
        t = np.arange(21) * 0.1
        slip3 = np.maximum(np.abs(t - 1.03) * 1e-5, 1e-12)
        ctx = self.context(self.traj(slip3=slip3),
                           [self.event(1.03, 3, "creep_reversal", "stick", "stick")])
        fig, caption = self.capture(fp.figure_slip, ctx)
        ax = fig.axes[0]
        marks = [line for line in ax.get_lines()
                 if line.get_marker() == "^" and len(line.get_xdata())]
        self.assertEqual([float(line.get_xdata()[0]) for line in marks], [1.03])
        # The legend's entry is a grey proxy, not the first wheel's colour.
        proxies = [line for line in ax.get_lines()
                   if line.get_marker() == "^" and not len(line.get_xdata())]
        self.assertEqual([line.get_color() for line in proxies], ["#777777"])
        self.assertIn("turns through or near zero", caption)
        self.assertIn("output sample nearest to it", caption)
        plotting.plt.close(fig)

    # 4. event lines in styles of their own, labels with 5 digits, merged
    def test_event_styles_and_labels(self):
        from matplotlib.lines import _get_dash_pattern
        from quasiroll_report import figures_paper as fp

        def shape(style):
            """The pattern's on-segments as dots and dashes: ('dash', 'dot') is
            dash-dotted whatever the lengths."""
            pattern = _get_dash_pattern(style)[1] or ()
            return tuple("dot" if on <= 1.5 else "dash" for on in pattern[::2])
        wheels = {shape(style) for _, style in plotting.WHEEL_STYLES}
        events = {shape(style) for _, style in fp._EVENT_LINES.values()}
        self.assertEqual(len(events), 3)
        self.assertFalse(events & wheels, (events, wheels))
        plotting.apply_style()
        fig = plotting.new_figure(8, 4.2)
        ax = fig.add_subplot()
        ax.plot([0, 20], [0, 1])
        _, _, _, texts = fp._draw_events(ax, [
            self.event(2.902958448, 1), self.event(2.9193454, 3, before="slide", after="stick"),
            *[self.event(2.9071446858, w, "solution_jump", "slide", "slide") for w in (1, 2, 3)],
            self.event(16.647243, 3, "creep_reversal", "stick", "stick")])
        self.assertEqual(texts, ["2.903 S1\n2.9071 J\n2.9193 S3", "16.647 R3"])
        plotting.plt.close(fig)

    # 5. Fig. 9: the weight line; vertical components of the contact forces
    def test_normal_forces_draw_the_weight(self):
        from quasiroll_report import figures_paper as fp
        plotting.apply_style()
        references = {"h": {"key": "robot{a=0.25};mass=5;gravity=9.8;mode=paper"}}
        ctx = self.context(self.traj(n1=np.full(21, 20.0)), [], references,
                           {"type": "plane", "height": 0.0})
        fig, caption = self.capture(fp.figure_normal_forces, ctx)
        weights = [line for line in fig.axes[0].get_lines()
                   if list(line.get_ydata()) == [49.0, 49.0]]
        self.assertEqual(len(weights), 1)
        self.assertIn("m g = 49 N", caption)
        self.assertIn("tractions have vertical components", caption)
        self.assertIn("balance m g within 3.67 N", caption)   # Σ N = 52.67 N here
        plotting.plt.close(fig)
        # On an incline the normals tilt: Σ F_z = Σ N cos β without tractions.
        incline = self.context(self.traj(), [], references,
                               {"type": "incline", "slope_deg": 20.0})
        vertical = fp.vertical_force_sum(incline, incline.primary, self.traj())
        self.assertAlmostEqual(float(vertical[0]), 49.0 * float(np.cos(np.radians(20.0))),
                               places=6)

    # 6. Fig. 10: internal forces, the net line, creeping wheels marked
    def test_longitudinal_traction_net_line_and_creep(self):
        from quasiroll_report import figures_paper as fp
        plotting.apply_style()
        ctx = self.context(self.traj(t1_lon=np.full(21, -10.0), t2_lon=np.full(21, 5.0),
                                     t3_lon=np.full(21, 5.5), slip1=np.full(21, 1e-9)),
                           [], eps=1e-8)
        fig, caption = self.capture(fp.figure_longitudinal_traction, ctx)
        lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
        self.assertTrue(np.allclose(lines["sum (net)"].get_ydata(), 0.5))
        grey = [line for line in fig.axes[0].get_lines()
                if line.get_color() == fp.CREEP_UNDERLAY]
        self.assertEqual(len(grey), 3)
        self.assertEqual([int(np.sum(np.isfinite(line.get_ydata()))) for line in grey],
                         [21, 0, 0])
        for text in ("internal, antagonistic forces", "scale with μ",
                     "fixed by the creep regularisation", "the net traction",
                     "wheel 1 100 %"):
            self.assertIn(text, caption)
        self.assertNotIn("must provide", caption)
        plotting.plt.close(fig)

    # 9. Fig. 11: the lateral tractions get their net line too
    def test_equal_curves_drawn_dashed_and_named(self):
        """Fig. 13: a method whose curve lies on an earlier one (ceres on
        newton) is drawn dashed over it and named, not hidden under it."""
        from quasiroll_report import figures_paper as fp
        runs, metrics = [], {}
        for method, scale in (("ceres/rk-projection/zoh", 1.0),
                              ("newton/rk-projection/zoh", 1.001),
                              ("slsqp/rk-projection/zoh", 2.0)):
            for mu in (0.2, 0.5, 0.8):
                rid = f"{method}-{mu}"
                runs.append(_base_row(run_id=rid, method=method, mu=mu))
                metrics[rid] = {"mean_total_traction": scale * 10 * mu}
        plotting.apply_style()
        fig = plotting.new_figure(4, 3)
        ax = fig.add_subplot()
        hidden = []
        fp._per_method_curve(ax, runs, metrics, "mean_total_traction", {}, hidden=hidden)
        self.assertEqual(hidden, [("newton/rk-projection/zoh", "ceres/rk-projection/zoh")])
        styles = {line.get_label(): line.get_linestyle() for line in ax.get_lines()}
        self.assertEqual(styles["newton/rk-projection/zoh"], "--")
        self.assertEqual(styles["slsqp/rk-projection/zoh"], "-")
        self.assertIn("paper: newton/rk-projection/zoh on ceres/rk-projection/zoh",
                      fp._hidden_text([{"scene": "paper", "hidden": hidden}]))
        plotting.plt.close(fig)

    def test_lateral_traction_net_line(self):
        from quasiroll_report import figures_paper as fp
        plotting.apply_style()
        ctx = self.context(self.traj(t1_lat=np.full(21, -4.0), t2_lat=np.full(21, 1.5),
                                     t3_lat=np.full(21, 2.0)), [], eps=1e-8)
        fig, caption = self.capture(fp.figure_lateral_traction, ctx)
        self.addCleanup(plotting.plt.close, fig)
        lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
        self.assertTrue(np.allclose(lines["sum (net)"].get_ydata(), -0.5))
        self.assertIn("Their sum (black dotted, the net traction) stays within "
                      "[-0.5, -0.5] N", caption)

    # 7. Figs. 13-14: the μ_min horizon; Fig. 13's rows and shared μ axes
    def test_mu_min_horizon_and_traction_rows(self):
        from quasiroll_report import figures_paper as fp
        manifest = self.manifest()
        for name in ("fig13_traction_vs_mu", "fig14_total_slip_vs_mu"):
            self.assertIn("paper needs μ ≥ 0.27 over 0–8 s", manifest[name]["caption"])
            self.assertEqual([p["mu_min_horizon"] for p in manifest[name]["data"]["panels"]],
                             [8.0, 8.0])
        caption = manifest["fig13_traction_vs_mu"]["caption"]
        self.assertIn("mean |longitudinal traction| only", caption)
        self.assertIn("total traction norm", caption)
        self.assertIn("scale with μ", caption)
        fig = plotting.new_figure(5, 4)
        ax = fig.add_subplot()
        ax.plot([0.2, 0.8], [1, 2])
        self.assertIn("(0–20 s)", fp._mu_min_line(ax, 0.43, 20.0).get_text())
        plotting.plt.close(fig)
        plotting.apply_style()
        fig, _ = self.capture(fp.figure_traction_vs_mu, self.fixture_context())
        top, bottom = fig.axes[0], fig.axes[1]
        self.assertTrue(top.get_shared_x_axes().joined(top, bottom))
        plotting.plt.close(fig)

    # 8. Fig. 6: the centre path under the contact paths, thinner
    def test_locus_centre_path_drawn_first_and_thinner(self):
        from quasiroll_report import figures_paper as fp
        plotting.apply_style()
        fig, _ = self.capture(fp.figure_locus, self.fixture_context())
        lines = {line.get_label(): line for line in fig.axes[0].get_lines()}
        centre, wheel1 = lines["platform centre"], lines["contact point wheel 1"]
        self.assertLess(centre.get_linewidth(), wheel1.get_linewidth())
        self.assertLess(centre.get_zorder(), wheel1.get_zorder())
        plotting.plt.close(fig)


class RefereeTest(unittest.TestCase):
    """Issue #21 item 8, the referee's smaller points (report side)."""

    def manifest(self):
        with open(os.path.join(Fixture.good, "report", "figures.json")) as handle:
            return {entry["name"]: entry for entry in json.load(handle)}

    def html(self):
        with open(os.path.join(Fixture.good, "report", "index.html"),
                  encoding="utf-8") as handle:
            return handle.read()

    # 1. sweep panels are titled by what is held fixed, never the swept value
    def test_sweep_panels_titled_by_fixed_parameters(self):
        manifest = self.manifest()
        for name in ("fig13_traction_vs_mu", "fig14_total_slip_vs_mu"):
            titles = [p["title"] for p in manifest[name]["data"]["panels"]]
            self.assertEqual(len(titles), 2, titles)
            for title in titles:
                self.assertNotIn("μ=", title)
                self.assertIn("Δt=0.1 s", title)
            self.assertIn("pvc mode", titles[1])
        labels = {name: [p["label"] for p in manifest[name]["data"]["panels"]]
                  for name in STABILITY_FIGURES}
        self.assertTrue(all("roughness" not in lab for lab in labels["fig_stability_roughness"]),
                        labels)
        self.assertTrue(all("μ=" not in lab for lab in labels["fig_stability_mu"]), labels)
        self.assertTrue(all("Δt" not in lab for lab in labels["fig_stability_dt"]), labels)
        self.assertIn("μ=0.5", labels["fig_stability_dt"][0])
        # A field that varies over the panel's rows is never taken from one row.
        rows = [_base_row(mu=0.3), _base_row(mu=0.5, dt=0.2)]
        label = problems.fixed_label(rows)
        self.assertNotIn("μ=", label)
        self.assertNotIn("Δt", label)
        self.assertIn("8 s", label)
        self.assertNotIn("μ=", problems.fixed_label(rows[:1], omit=("mu",)))

    # 2. the μ_min label stays inside its axes, clear of the title
    def assert_inside_axes_clear_of_title(self, fig, ax, needle):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        texts = [t for t in ax.texts if needle in t.get_text()]
        self.assertEqual(len(texts), 1, [t.get_text() for t in ax.texts])
        box = texts[0].get_window_extent(renderer)
        frame = ax.get_window_extent(renderer)
        self.assertGreaterEqual(box.y0, frame.y0 - 1)
        self.assertLessEqual(box.y1, frame.y1 + 1)
        self.assertGreaterEqual(box.x0, frame.x0 - 1)
        self.assertFalse(box.overlaps(ax.title.get_window_extent(renderer)))

    # 2a. on a stability panel the label is a tick on the top edge, clear of
    # the title and of the cells' fractions (it hid them inside the cells)
    def assert_top_tick_clear(self, fig, ax, needle):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        labels = [t for child in ax.child_axes for t in child.get_xticklabels()
                  if needle in t.get_text()]
        self.assertEqual(len(labels), 1)
        box = labels[0].get_window_extent(renderer)
        self.assertGreaterEqual(box.y0, ax.get_window_extent(renderer).y1 - 1)
        self.assertFalse(box.overlaps(ax.title.get_window_extent(renderer)))
        for cell in ax.texts:
            self.assertFalse(box.overlaps(cell.get_window_extent(renderer)),
                             cell.get_text())

    def test_mu_min_label_inside_axes(self):
        from quasiroll_report import figures_methods, figures_paper
        plotting.apply_style()
        for rows in (["a/b/zoh"], ["a/b/zoh", "c/d/zoh", "e/f/zoh"]):
            panel = {"rows": rows, "values": [0.1, 0.3, 0.5], "numeric": True, "log": False,
                     "cells": {(rows[0], j): {"cls": "success", "detail": "", "label": "1"}
                               for j in range(3)},
                     "label": "paper · 8 s", "mu_min": 0.43, "limits": []}
            fig = plotting.new_figure(7, 1.3 + 0.3 * len(rows))
            ax = fig.add_subplot()
            figures_methods._draw_stability_panel(ax, panel, "μ [-]", "mu")
            self.assert_top_tick_clear(fig, ax, "μ_min")
            plotting.plt.close(fig)
        fig = plotting.new_figure(5, 4)
        ax = fig.add_subplot()
        ax.plot([0.2, 0.8], [1, 2])
        ax.set_title("paper · 8 s\ntotal traction per method")
        figures_paper._mu_min_line(ax, 0.43)
        self.assert_inside_axes_clear_of_title(fig, ax, "μ_min")
        plotting.plt.close(fig)

    # 2b. a cause legend with the longest label ends inside its figure
    def test_cause_legend_inside_figure(self):
        from quasiroll_report import figures_methods
        plotting.apply_style()
        rows = ["newton/rk-projection/zoh", "ceres/rk-baumgarte/coupled"]
        cells = {(rows[0], 0): {"cls": "success", "detail": ""},
                 (rows[0], 1): {"cls": "model", "detail": "quasi_static_invalid"},
                 (rows[1], 0): {"cls": "numerical", "detail": "shared_solver_failure"},
                 (rows[1], 1): {"cls": "physical", "detail": "degenerate_contact"}}
        for cell in cells.values():
            cell.update(label="1", status="")
        chart = {"axis": "roughness", "axis_label": "roughness [-]",
                 "group": "stability_roughness",
                 "panels": [{"scene": "paper", "rows": rows, "values": [1, 8],
                             "cells": cells,
                             "label": "paper · 6 s", "mu_min": float("nan"),
                             "limits": []}]}
        captured = {}
        original = plotting.save_figure

        def keep(fig, *args, **kwargs):
            fig.canvas.draw()
            captured["figure"] = fig.bbox.x1
            captured["legends"] = [leg.get_window_extent().x1
                                   for ax in fig.axes if ax.get_legend()
                                   for leg in [ax.get_legend()]]
            captured["labels"] = [t.get_text() for ax in fig.axes if ax.get_legend()
                                  for t in ax.get_legend().get_texts()]
            plotting.plt.close(fig)
            return types.SimpleNamespace(notes=[])

        figures_methods.save_figure = keep
        try:
            figures_methods._stability_figure(
                types.SimpleNamespace(runs=[], out_dir=None), chart)
        finally:
            figures_methods.save_figure = original
        self.assertTrue(captured.get("legends"), captured)
        self.assertTrue(any("quasi-static domain" in t for t in captured["labels"]),
                        captured["labels"])
        for right in captured["legends"]:
            self.assertLessEqual(right, captured["figure"])

    # 3. numeric axes by value; the RK4 limit on the σ·Δt axis
    def test_numeric_axes_and_rk4_limit(self):
        manifest = self.manifest()
        sigma = manifest["fig_stability_sigma_dt"]
        for panel in sigma["data"]["panels"]:
            self.assertTrue(panel["numeric"])
            self.assertEqual(panel["limits"], [2.785])
        self.assertIn("h = Δt/substeps", sigma["caption"])
        self.assertIn("σ·h = 2.785", sigma["caption"])
        for name in ("fig_stability_mu", "fig_stability_dt"):
            self.assertTrue(all(p["numeric"] for p in manifest[name]["data"]["panels"]))
        # the table flags the σ·Δt columns beyond the limit (the fixture's 3)
        html = self.html()
        self.assertIn('title="beyond the RK4 limit σ·h = 2.785">3*</th>', html)
        self.assertIn("<th>1.5</th>", html)
        self.assertIn("σ·Δt &gt; 2.785", html)
        # substeps: h = Δt/substeps, so the line sits at 2.785·substeps
        rk4 = _base_row(dae_options=json.dumps({"baumgarte_sigma": 5, "rk_method": "rk4"}),
                        substeps=4.0)
        adaptive = _base_row(dae_options=json.dumps({"baumgarte_sigma": 5,
                                                     "rk_method": "dp54"}))
        self.assertEqual([(round(x, 6), n) for x, n in sel.rk4_limit_lines([rk4, adaptive])],
                         [(11.14, 4)])
        # drawn by value on a log axis, with the limit line
        from quasiroll_report import figures_methods
        values = [0.05, 0.5, 1.0, 40.0]
        panel = {"rows": ["a/b/zoh"], "values": values, "numeric": True, "log": True,
                 "cells": {("a/b/zoh", j): {"cls": "success", "detail": "", "label": "1"}
                           for j in range(4)},
                 "label": "x", "mu_min": float("nan"), "limits": [(2.785, 1)]}
        fig = plotting.new_figure(8, 1.6)
        ax = fig.add_subplot()
        figures_methods._draw_stability_panel(ax, panel, "σ·Δt [-]", "sigma_dt")
        self.assertEqual(ax.get_xscale(), "log")
        self.assertEqual([float(t) for t in ax.get_xticks()], values)
        lo, hi = ax.get_xlim()
        self.assertTrue(lo < 0.05 and hi > 40.0, (lo, hi))
        centres = sorted(p.get_x() + p.get_width() / 2 for p in ax.patches)
        self.assertEqual(len(centres), 4)
        # bands sit by value: the 0.5..1 gap is narrow, 1..40 wide
        widths = [p.get_width() for p in sorted(ax.patches, key=lambda p: p.get_x())]
        self.assertLess(widths[1], widths[3])
        self.assertTrue(any(list(line.get_xdata()) == [2.785, 2.785] for line in ax.lines))
        plotting.plt.close(fig)

    # 4. no σ for integrators without a Baumgarte gain
    def test_no_sigma_without_baumgarte_gain(self):
        manifest = self.manifest()
        legend = manifest["fig15_stabilisation"]["data"]["legend"]
        projection = [t for t in legend if t.startswith("rk-projection")]
        baumgarte = [t for t in legend if t.startswith("rk-baumgarte")]
        self.assertTrue(projection and baumgarte, legend)
        self.assertNotIn("σ", projection[0])
        self.assertIn("σ=5", baumgarte[0])
        data = manifest["fig_stability_sigma_dt"]["data"]
        self.assertEqual(data["left_out"], ["newton/rk-projection/zoh"])
        self.assertNotIn("newton/rk-projection/zoh", [r for p in data["panels"]
                                                      for r in p["rows"]])
        self.assertIn("without a Baumgarte gain", manifest["fig_stability_sigma_dt"]["caption"])
        with_gain = _base_row(dae_options='{"baumgarte_sigma":5,"rk_method":"rk4"}')
        without = _base_row(dae_options='{"projection_tolerance":1e-12,"rk_method":"rk4"}')
        self.assertTrue(data_module.has_dae_option(with_gain, "baumgarte_sigma"))
        self.assertFalse(data_module.has_dae_option(without, "baumgarte_sigma"))

    # 5. a blow-up status reads as numerical in the summary
    def test_summary_status_shows_cause_class(self):
        html = self.html()
        summary = html[html.index("Summary"):html.index("Fastest")]
        self.assertIn("INFEASIBLE_FRICTION (numerical: drift_blowup)", summary)
        self.assertIn("DEGENERATE_CONTACT (numerical: baumgarte_instability)", summary)
        self.assertIn("INFEASIBLE_FRICTION (physical: friction_limit)", summary)
        self.assertNotRegex(summary, r"INFEASIBLE_FRICTION \d")
        blowup = _base_row(status="drift_exceeded")
        self.assertEqual(sel.status_text(blowup), "drift_exceeded (numerical: drift_blowup)")
        friction = _base_row(status="INFEASIBLE_FRICTION", cause="numerical",
                             cause_detail="baumgarte_instability")
        self.assertEqual(sel.status_text(friction),
                         "INFEASIBLE_FRICTION (numerical: baumgarte_instability)")
        self.assertEqual(sel.status_text(_base_row(status="INFEASIBLE_FRICTION")),
                         "INFEASIBLE_FRICTION (unclassified)")

    # 6. Fig. 5: one method in both panels, camber shown in degrees
    def test_fig5_one_method_and_camber_labels(self):
        entry = self.manifest()["fig05_snapshots"]
        panels = entry["data"]["panels"]
        self.assertEqual(len(panels), 2)
        self.assertEqual(panels[0]["method"], panels[1]["method"])
        self.assertIn(f"same method, {panels[0]['method']}", entry["caption"])
        for panel in panels:
            self.assertEqual([lab[:3] for lab in panel["camber_labels"]], ["δ2=", "δ3="])
            self.assertTrue(all(lab.endswith("°") for lab in panel["camber_labels"]))
        # The paper scene's own pick (finest Δt, m1) is not run in pvc mode:
        # the pair is the method both ran (m2), not m1 beside m3.
        runs = [_base_row(run_id="a", method="m1", dt=0.05),
                _base_row(run_id="b", method="m2", dt=0.1),
                _base_row(run_id="c", method="m2", dt=0.1, scene="paper_pvc"),
                _base_row(run_id="d", method="m3", dt=0.05, scene="paper_pvc")]
        self.assertEqual(sel.paper_run(runs, lambda r: True)["run_id"], "a")
        paper, pvc = sel.snapshot_pair(runs, lambda r: True, "paper_pvc")
        self.assertEqual((paper["run_id"], pvc["run_id"]), ("b", "c"))


class ReplayPageTest(unittest.TestCase):
    """Issue #21 item 8.7: the 3D replay's ?run=<run_id>, scales, per-frame
    values and friction cones."""

    def setUp(self):
        if not os.path.isfile("/usr/share/javascript/three/three.min.js"):
            self.skipTest("libjs-three not installed")
        self.folder = os.path.join(Fixture.good, "report", "replay")
        with open(os.path.join(self.folder, "data.js"), encoding="utf-8") as handle:
            text = handle.read()
        self.data = json.loads(text[text.index("=") + 1:].rstrip().rstrip(";"))
        with open(os.path.join(self.folder, "index.html"), encoding="utf-8") as handle:
            self.page = handle.read()

    def test_frame_values_cones_and_scales(self):
        from quasiroll_report import replay
        for run in self.data:
            self.assertGreater(run["scale_bar"], 0)
            self.assertGreater(run["force_bar"], 0)
            self.assertEqual(run["force_bar"], replay.nice_length(run["force_bar"]))
            for frame in run["frames"][::25]:
                for key, size in (("v", 3), ("w", 3), ("n", 3), ("lon", 3), ("lat", 3),
                                  ("camber", 2), ("normals", 3)):
                    self.assertEqual(len(frame[key]), size, key)
                for normal in frame["normals"]:
                    self.assertAlmostEqual(float(np.linalg.norm(normal)), 1.0, places=5)
                    self.assertGreater(normal[2], 0.5)
        self.assertEqual(replay.nice_length(0.37), 0.25)
        self.assertEqual(replay.nice_length(7.0), 5.0)
        for needle in ("AxesHelper", "ConeGeometry", "force_bar", 'id="info"',
                       "camber", "scale_bar"):
            self.assertIn(needle, self.page)
        self.assertNotIn("http://", self.page.replace("http://www.w3.org", ""))
        self.assertNotIn("https://", self.page)

    def test_run_parameter_picks_by_run_id(self):
        if not shutil.which("node"):
            self.skipTest("node not installed")
        start = self.page.index("function pickRun(")
        end = self.page.index("window.quasirollPickRun")
        ids = [d["run_id"] for d in self.data]
        script = (self.page[start:end] + "var runs = " + json.dumps([{"run_id": i} for i in ids])
                  + ";\nconsole.log(JSON.stringify([pickRun(runs, null), pickRun(runs, "
                  + json.dumps(ids[-1]) + "), pickRun(runs, '1'), pickRun(runs, '9'), "
                  "pickRun(runs, 'no-such-run')]));")
        out = subprocess.run(["node", "-e", script], capture_output=True, text=True,
                             timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertEqual(json.loads(out.stdout), [0, len(ids) - 1, 1, len(ids) - 1, -1])

    def test_run_parameter_in_browser(self):
        browser = shutil.which("chromium")
        if not browser:
            self.skipTest("chromium not installed")
        wanted = self.data[-1]["run_id"]
        profile = tempfile.mkdtemp(prefix="quasiroll_replay_profile_")
        try:
            out = subprocess.run(
                [browser, "--headless", "--no-sandbox", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--no-first-run",
                 "--disable-background-networking", f"--user-data-dir={profile}",
                 "--virtual-time-budget=10000", "--window-size=1000,640", "--dump-dom",
                 "file://" + os.path.join(self.folder, "index.html") + f"?run={wanted}"],
                capture_output=True, text=True, timeout=180)
        finally:
            shutil.rmtree(profile, ignore_errors=True)
        self.assertIn('data-ready="1"', out.stdout, out.stdout[-2000:])
        info = out.stdout[out.stdout.index('<div id="info">'):]
        self.assertTrue(info.startswith(f'<div id="info">run {wanted}\nt = '), info[:200])
        self.assertIn("camber", info[:1000])
        self.assertIn("|t|/(mu N)", info[:1000])


class BadInputTest(unittest.TestCase):
    def assert_one_line_error(self, result, *needles):
        self.assertEqual(result.returncode, 2, result.stderr)
        lines = result.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, result.stderr)
        self.assertTrue(lines[0].startswith("make_report: "), lines[0])
        for needle in needles:
            self.assertIn(needle, lines[0])
        self.assertNotIn("Traceback", result.stderr)

    def test_missing_column(self):
        target = Fixture.copy("missing_column")
        edit_csv(os.path.join(target, "runs.csv"), drop_column("err_pos_rms"))
        result = run_report(target)
        self.assert_one_line_error(result, "runs.csv is missing column 'err_pos_rms'")

    def test_missing_runs_csv(self):
        target = Fixture.copy("no_runs")
        os.remove(os.path.join(target, "runs.csv"))
        self.assert_one_line_error(run_report(target), "runs.csv not found")

    def test_empty_runs_csv(self):
        target = Fixture.copy("empty_runs")
        open(os.path.join(target, "runs.csv"), "w").close()
        self.assert_one_line_error(run_report(target), "runs.csv is empty")

    def test_header_only(self):
        target = Fixture.copy("header_only")
        edit_csv(os.path.join(target, "runs.csv"), lambda header, _: (header, []))
        self.assert_one_line_error(run_report(target), "no runs")

    def test_no_successful_run(self):
        target = Fixture.copy("all_failed")
        edit_csv(os.path.join(target, "runs.csv"),
                 set_column("status", "SOLVER_FAILURE"))
        self.assert_one_line_error(run_report(target), "no successful run")

    def test_non_numeric_field(self):
        target = Fixture.copy("bad_number")
        edit_csv(os.path.join(target, "runs.csv"),
                 set_column("dt", "fast", first_only=True))
        self.assert_one_line_error(run_report(target), "'dt'", "fast")

    def test_missing_results_dir(self):
        self.assert_one_line_error(run_report(os.path.join(Fixture.root, "nope")),
                                   "not found")

    def test_trajectory_missing_column(self):
        target = Fixture.copy("bad_trajectory")
        traj_dir = os.path.join(target, "trajectories")
        for name in os.listdir(traj_dir):
            edit_csv(os.path.join(traj_dir, name), drop_column("drift"))
        self.assert_one_line_error(run_report(target), "missing column 'drift'")

    def test_missing_mu_sweep_placeholder_unless_strict(self):
        target = Fixture.copy("no_mu_sweep")

        def no_mu_sweep(header, rows):
            group = header.index("suite_group")
            return header, [r for r in rows if r[group] != "mu_sweep"]
        edit_csv(os.path.join(target, "runs.csv"), no_mu_sweep)
        self.assert_one_line_error(run_report(target, "--strict"), "figures 13-14")
        allowed = run_report(target)
        self.assertEqual(allowed.returncode, 0, allowed.stderr)
        self.assertNotIn("Traceback", allowed.stderr)


class OptionalInputTest(unittest.TestCase):
    def test_without_terrain_meta_and_optional_columns(self):
        target = Fixture.copy("minimal")
        shutil.rmtree(os.path.join(target, "terrains"))
        os.remove(os.path.join(target, "meta.json"))
        out = os.path.join(Fixture.root, "minimal_out")
        result = run_report(target, "--out", out)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(result.stdout.strip().splitlines()[-1],
                         os.path.join(out, "index.html"))
        with open(os.path.join(out, "index.html"), encoding="utf-8") as handle:
            html = handle.read()
        self.assertIn("without a terrain surface", html)
        self.assertIn("unknown", html)

    def test_quoted_stop_reason_with_commas(self):
        runs = read_runs(Fixture.good)[0]
        reasons = [r["stop_reason"] for r in runs if r["status"] == "INFEASIBLE_FRICTION"]
        self.assertTrue(reasons)
        self.assertIn(",", reasons[0])


def main():
    suite = unittest.defaultTestLoader.loadTestsFromModule(sys.modules[__name__])
    result = unittest.TextTestRunner(verbosity=2, stream=sys.stdout).run(suite)
    failed = len(result.failures) + len(result.errors) + len(result.unexpectedSuccesses)
    passed = result.testsRun - failed - len(result.skipped)
    print(f"{passed} passed, {failed} failed")
    return 0 if failed == 0 and result.testsRun > 0 else 1


class FailedTextTest(unittest.TestCase):
    """The μ-sweep captions' failure summary: with runs.csv err_stop_t
    (t_reached − t_ref of a physical stop) it says how far the methods
    stopped from the reference's located stop; older files without the
    column keep the plain count."""

    def rows(self, lags):
        return [dict(scene="paper_pvc", mu=0.3, status="INFEASIBLE_FRICTION",
                     cause="physical", cause_detail="friction_limit",
                     method=f"m{k}", err_stop_t=lag)
                for k, lag in enumerate(lags)]

    def test_stop_lags_are_spanned(self):
        from quasiroll_report import figures_paper
        text = figures_paper._failed_text(self.rows([1.31e-3, 4e-8]))
        self.assertEqual(text, "failed: paper_pvc μ=0.3 physical friction_limit "
                         "(2 methods, stop − reference's stop 4.00e-08 to 0.00131 s)")

    def test_without_the_column_the_count_stays(self):
        from quasiroll_report import figures_paper
        rows = self.rows([float("nan"), float("nan")])
        for r in rows[1:]:
            del r["err_stop_t"]
        self.assertEqual(figures_paper._failed_text(rows),
                         "failed: paper_pvc μ=0.3 physical friction_limit (2 methods)")


class BorrowedCauseTextTest(unittest.TestCase):
    """A stability cell coloured by the reference's physical stop while its
    run ended in SOLVER_FAILURE is said to be so in the caption."""

    def test_solver_status_cells_are_counted(self):
        from quasiroll_report import figures_methods
        cells = [dict(cls="physical", status="SOLVER_FAILURE"),
                 dict(cls="physical", status="INFEASIBLE_FRICTION"),
                 dict(cls="numerical", status="SOLVER_FAILURE"),
                 dict(cls="physical", status="SINGULAR")]
        text = figures_methods._borrowed_cause_text(cells)
        self.assertTrue(text.startswith(" 2 physical cells ended in a solver status"))
        self.assertIn("err_stop_t", text)
        self.assertEqual(figures_methods._borrowed_cause_text(cells[1:2]), "")

class FailureStripTest(unittest.TestCase):
    """Figs. 13-14 mark failed runs by crosses in a grey strip along the
    bottom; the data must lie above it, or a cross reads as a value (it sat
    on the pvc traction curve at 8.3 N)."""

    def test_data_lie_above_the_strip(self):
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from quasiroll_report import figures_paper as fp
        for log in (False, True):
            fig, ax = plt.subplots()
            ys = [1.3e-7, 1e-3] if log else [8.3, 32.0]
            ax.plot([0.5, 0.8], ys)
            if log:
                ax.set_yscale("log")
            failed = [dict(mu=0.2, method="newton/rk-projection/zoh", status="INFEASIBLE_FRICTION",
                           cause="physical", cause_detail="friction_limit")]
            fp._mark_failures(ax, failed)
            fp._room_for_failures([ax])
            lowest = ax.transAxes.inverted().transform(
                ax.transData.transform((0.5, min(ys))))[1]
            self.assertGreater(lowest, 0.12, log)
            plt.close(fig)


class EventFindingsTest(unittest.TestCase):
    """The key finding on the located events themselves: unlocated events,
    one event recorded twice, brackets closing onto an output sample (each
    a defect of the location once, docs/model.md §8.6)."""

    class Store:
        def __init__(self, events):
            self.events = events

        def switches(self, run):
            return self.events.get(run["run_id"])

    @staticmethod
    def event(t, wheel=1, kind="switch", located=True, lower=None):
        return {"t": t, "wheel": wheel, "from": "stick", "to": "slide",
                "located": located, "kind": kind,
                "t_lower": t - 7e-10 if lower is None else lower, "t_upper": t}

    def test_clean_events_read_clean(self):
        from quasiroll_report import findings
        runs = [{"run_id": "a", "dt": 0.05}, {"run_id": "b", "dt": 0.05}]
        store = self.Store({"a": [self.event(2.9031), self.event(9.0933, 3, "creep_reversal")],
                            "b": None})
        text = findings.event_findings(runs, store)[0]
        self.assertIn("1 runs): 1 creep reversal, 1 switch rows", text)
        self.assertIn("every one located to the switch tolerance, none recorded twice",
                      text)

    def test_each_defect_is_named(self):
        from quasiroll_report import findings
        runs = [{"run_id": "loose", "dt": 0.05}, {"run_id": "twice", "dt": 0.025},
                {"run_id": "failed", "dt": 0.4}]
        store = self.Store({
            # A bracket closing onto the sample at 3.05 s (and its twin back).
            "loose": [self.event(3.05, 3, lower=3.05 - 7.45e-10),
                      self.event(3.05 + 7.45e-10, 3, lower=3.05)],
            "twice": [self.event(9.0932758512, 3, "creep_reversal"),
                      self.event(9.0932758518, 3, "creep_reversal")],
            "failed": [self.event(1.1109, located=False, lower=1.1107)],
            # Three wheels' rows of one jump are not twins.
        })
        store.events["failed"] += [self.event(2.0, w, "solution_jump") for w in (1, 2, 3)]
        text = findings.event_findings(runs, store)[0]
        self.assertIn("1 not located (their solves failed inside the bracket) in 1 runs, "
                      "e.g. failed wheel 1 at 1.1109 s", text)
        self.assertIn("2 recorded twice", text)
        self.assertIn("e.g. loose wheel 3", text)
        self.assertIn("2 with a bracket closing onto an output sample", text)
        self.assertNotIn("every one located", text)


class StopLocationFindingsTest(unittest.TestCase):
    """The key finding on located stops: per coupling, the span of
    err_stop_t, and the runs farther from the reference's stop than the
    reference's own check (|ref_check_t_diff|) puts it."""

    def row(self, coupling, lag, check, method="newton + rk-projection"):
        return dict(coupling=coupling, err_stop_t=lag, ref_check_t_diff=check,
                    method=method, scene="paper_pvc", suite_group="mu_sweep")

    def test_spans_per_coupling_and_flags_runs_beyond_the_check(self):
        from quasiroll_report import findings
        runs = [self.row("coupled", 3.6e-8, 6e-6), self.row("coupled", -2.6e-4, 2.4e-4),
                self.row("zoh", 1.3e-3, 6e-6, method="newton + ida"),
                self.row("zoh", 9e-4, 6e-6),
                self.row("zoh", float("nan"), 6e-6)]  # not a physical stop
        text = findings.stop_location_findings(runs)
        self.assertEqual(len(text), 2)
        self.assertEqual(
            text[0], "Located physical stops, coupled: 2 runs stop -2.60e-04 to 3.60e-08 s "
            "from the reference's stop (median |difference| 1.30e-04 s); 1 differ by more "
            "than the reference's own uncertainty (|ref_check_t_diff|), so the difference "
            "is the method's, the largest newton + rk-projection on paper_pvc (mu_sweep): "
            "-2.60e-04 s.")
        self.assertIn("zoh: 2 runs stop 9.00e-04 to 0.0013 s", text[1])
        self.assertIn("2 differ by more than the reference's own uncertainty", text[1])
        self.assertIn("the method's (the hold's lag), the largest newton + ida", text[1])

    def test_without_the_columns_nothing_is_said(self):
        from quasiroll_report import findings
        self.assertEqual(findings.stop_location_findings([dict(coupling="zoh")]), [])


class MethodFigureRefereeTest(unittest.TestCase):
    """The referee's defects of the method figures (work-precision, drift,
    Fig. 15, stability charts): each check failed before its fix."""

    def test_step_drift_panel_draws_dots_not_bars(self):
        """A bar on a log axis reads as its length, which the axis' start sets:
        the representatives' two drift maxima are dots at their values."""
        from quasiroll_report import figures_methods as fm
        plotting.apply_style()
        fig = plotting.new_figure(4, 3)
        ax = fig.add_subplot()
        fm._plot_step_drift_dots(ax, [("ida", 7.9e-13, 7.6e-12), ("rk-projection", 1.4e-13, 3.5e-7)])
        self.assertEqual(len(ax.patches), 0)
        dots = {line.get_label(): list(line.get_xdata()) for line in ax.get_lines()
                if line.get_marker() in ("o", "D")}
        self.assertEqual(dots["at the samples (returned states)"], [7.9e-13, 1.4e-13])
        self.assertEqual(dots["within the steps, before projection"], [7.6e-12, 3.5e-7])
        plotting.plt.close(fig)

    def test_rk4_limit_line_only_over_rk4_rows(self):
        """The RK4 limit says nothing about an IDA row: the line spans the
        fixed-step RK4 rows only."""
        from quasiroll_report import figures_methods as fm
        rk4 = _base_row(method="n/rk-baumgarte/zoh", dae="rk-baumgarte",
                        dae_options=json.dumps({"baumgarte_sigma": 5, "rk_method": "rk4"}))
        ida = _base_row(method="n/ida/zoh", dae="ida",
                        dae_options=json.dumps({"baumgarte_sigma": 5}))
        limit_rows = sel.rk4_limit_rows([rk4, ida], lambda r: r["method"])
        self.assertEqual(limit_rows, {1: ["n/rk-baumgarte/zoh"]})
        rows = ["n/ida/coupled", "n/ida/zoh", "n/rk-baumgarte/coupled", "n/rk-baumgarte/zoh"]
        plotting.apply_style()
        fig = plotting.new_figure(7, 2.5)
        ax = fig.add_subplot()
        panel = {"rows": rows, "values": [1.0, 2.5, 3.0, 10.0], "numeric": True, "log": True,
                 "cells": {(r, j): {"cls": "success", "detail": "", "label": "1"}
                           for r in rows for j in range(4)},
                 "label": "x", "mu_min": float("nan"), "limits": [(2.785, 1)],
                 "limit_rows": {1: rows[2:]}}
        fm._draw_stability_panel(ax, panel, "σ·Δt [-]", "sigma_dt")
        spans = [seg for coll in ax.collections if coll.get_linestyle()[0][1]
                 for seg in coll.get_segments()]
        self.assertEqual(len(spans), 1)
        self.assertAlmostEqual(spans[0][0][0], 2.785)
        self.assertEqual(sorted([spans[0][0][1], spans[0][1][1]]), [1.5, 3.5])
        plotting.plt.close(fig)

    @staticmethod
    def _wp_row(method, dt, err, wall, tol=1e-6):
        nlp, dae, coupling = method.split("/")
        return _base_row(run_id=f"{method}-{dt}-{tol}", method=method, nlp=nlp, dae=dae,
                         coupling=coupling, dt=dt, tol=tol, err_pos_rms=err,
                         err_force_rms=err, wall_s=wall)

    def _panel(self, rows, estimate, metric="err_pos_rms", unresolved=float("nan")):
        from quasiroll_report import figures_methods as fm
        plotting.apply_style()
        fig = plotting.new_figure(6, 4)
        ax = fig.add_subplot()
        problem = {"rows": rows, "label": "p", "t_end": 8.0, "ref_err_est": estimate}
        out = fm._work_precision_panel(ax, problem, metric, "error", False, {}, unresolved)
        fig.canvas.draw()
        self.addCleanup(plotting.plt.close, fig)
        return ax, out

    def manifest(self):
        with open(os.path.join(Fixture.good, "report", "figures.json")) as handle:
            return {entry["name"]: entry for entry in json.load(handle)}

    # 1. the reference's estimate left of every point is inside the axis
    def test_reference_estimate_left_of_the_points_is_drawn(self):
        rows = [self._wp_row("a/b/zoh", dt, 1e-3 * dt, 0.1 / dt) for dt in (0.2, 0.1, 0.05)]
        ax, _ = self._panel(rows, 1e-9, unresolved=1e-9)
        lo, hi = ax.get_xlim()
        self.assertLess(lo, 1e-9)
        self.assertGreater(hi, 2e-4)
        self.assertTrue(any(list(line.get_xdata()) == [1e-9, 1e-9]
                            and line.get_linestyle() == ":" for line in ax.lines))

    # 1. a measured floor too narrow to see gets a line of fixed width
    def test_narrow_floor_band_is_drawn_visible(self):
        rows = ([self._wp_row("a/b/zoh", dt, 1e-8 / 0.05 * dt, 0.1 / dt)
                 for dt in (0.2, 0.1, 0.05)]
                + [self._wp_row("c/d/zoh", dt, 1.01e-8 / 0.05 * dt ** 4 * 8000, 0.2 / dt)
                   for dt in (0.4, 0.2, 0.05)])
        ax, (_, _, floor, narrow) = self._panel(rows, float("nan"))
        self.assertAlmostEqual(floor[1] / floor[0], 1.01, places=6)
        self.assertTrue(narrow)
        self.assertTrue(any(line.get_linewidth() == 4 for line in ax.lines))

    # 2. below the reference's estimate errors tie: only time ranks them
    def test_points_below_the_reference_estimate_are_tied(self):
        fast = {"err": 5e-10, "wall": 1.0, "wall_q1": 1.0, "wall_q3": 1.0}
        accurate = {"err": 1e-11, "wall": 2.0, "wall_q1": 2.0, "wall_q3": 2.0}
        coarse = {"err": 1e-6, "wall": 0.1, "wall_q1": 0.1, "wall_q3": 0.1}
        points = [fast, accurate, coarse]
        self.assertEqual(len(sel.non_dominated(points)), 3)   # unresolved order decides
        front = sel.non_dominated(points, floor=6e-10)
        self.assertIn(fast, front)
        self.assertIn(coarse, front)
        self.assertNotIn(accurate, front)
        # a resolved point within 1 % of the floor but slower is dominated: a
        # tie in error does not keep a slow point on the front
        self.assertTrue(sel.dominates(fast, dict(accurate, err=6.05e-10), floor=6e-10))
        # the panel: hatched below the estimate, one ring there
        rows = [self._wp_row("a/b/zoh", 0.1, 5e-10, 1.0), self._wp_row("c/d/zoh", 0.1, 1e-11, 2.0),
                self._wp_row("e/f/zoh", 0.1, 1e-6, 0.1)]
        ax, (_, front, _, _) = self._panel(rows, 6e-10, unresolved=6e-10)
        self.assertEqual(sorted(p["err"] for p in front), [5e-10, 1e-6])
        self.assertTrue(any(patch.get_hatch() == "////" for patch in ax.patches))

    # 3. force errors at round-off level tie at 1e3·ε·|N|
    def test_force_round_off_floor(self):
        self.assertAlmostEqual(sel.roundoff_floor(16.0), 1e3 * np.finfo(float).eps * 16.0)
        self.assertTrue(np.isnan(sel.roundoff_floor(float("nan"))))
        floor = sel.roundoff_floor(16.0)
        rows = [self._wp_row("a/b/zoh", 0.1, 1e-15, 2.0), self._wp_row("c/d/zoh", 0.1, 3e-15, 1.0),
                self._wp_row("e/f/zoh", 0.1, 1e-9, 0.5)]
        ax, (_, front, _, _) = self._panel(rows, float("nan"), "err_force_rms", floor)
        self.assertEqual(sorted(p["err"] for p in front), [3e-15, 1e-9])
        self.assertTrue(any(line.get_linestyle() == "-." for line in ax.lines))
        # the fixture's force panels: the floor from a trajectory's forces
        manifest = self.manifest()["fig_work_precision"]
        force = [p for p in manifest["data"]["panels"] if p["metric"] == "err_force_rms"]
        self.assertTrue(force)
        for panel in force:
            self.assertTrue(0 < panel["unresolved_below"] < 1e-10, panel["unresolved_below"])
        self.assertIn("force round-off floor", manifest["caption"])

    # 4. the zoh order is measured, O(Δt) claimed only where observed
    def test_zoh_order_sentence_is_measured(self):
        from quasiroll_report import figures_methods as fm

        def line(order, dae):
            return [{"dt": dt, "tol": 1e-6, "err": 1e-3 * dt ** order, "coupling": "zoh",
                     "dae": dae} for dt in (0.4, 0.2, 0.1, 0.05)]
        orders = sel.observed_orders({"x": line(4.0, "rk"), "short": line(1.0, "rk")[:2]})
        self.assertEqual(list(orders), ["x"])
        self.assertAlmostEqual(orders["x"], 4.0)
        text = fm._hold_order_text([({"label": "A"}, {"n/rk/zoh": line(1.0, "rk")}),
                                    ({"label": "B"}, {"n/rk/zoh": line(4.0, "rk"),
                                                      "n/cv/zoh": line(1.0, "cv")})])
        self.assertIn("O(Δt)", text)
        self.assertIn("observed on A (zoh orders 1.00 to 1.00)", text)
        self.assertIn("Not so on B (zoh orders per integrator: cv 1.0, rk 4.0)", text)
        self.assertNotIn("however accurate its integrator (hold error)", text)
        caption = self.manifest()["fig_work_precision"]["caption"]
        self.assertIn("its error falls only as O(Δt) however accurate its integrator: "
                      "observed on", caption)

    # 5. the omission note names only methods of the problems drawn
    def test_failed_note_only_names_the_drawn_problems(self):
        manifest = self.manifest()
        for name in ("fig_work_precision", "fig_drift"):
            caption = manifest[name]["caption"]
            self.assertIn(FAILED_ONLY, caption, name)
            self.assertNotIn(FAILED_VARIANT, caption, name)   # stability_sigma_dt only
        runs, _ = read_runs(Fixture.good)
        problems = sel.work_precision_problems(runs)
        self.assertEqual(sel.failed_only_in(runs, problems), [FAILED_ONLY])

    # 6. Fig. 15: bounded only with a plateau; within-step drift for both
    def test_stabilisation_caption_states_what_the_data_show(self):
        from quasiroll_report import figures_methods as fm
        t = np.linspace(0.0, 20.0, 201)
        self.assertGreater(fm.late_growth(t, 1e-10 * (1 + t)), fm.PLATEAU_GROWTH)
        self.assertAlmostEqual(fm.late_growth(t, 1e-10 * (1 - np.exp(-t))), 1.0, places=3)
        entry = self.manifest()["fig15_stabilisation"]
        caption = entry["caption"]
        self.assertIn("Like with like, within the steps before any projection "
                      "(drift_step_max, the marks at the right edge)", caption)
        self.assertTrue("levels off (" in caption or "still growing at t_end" in caption)
        self.assertEqual(sorted(entry["data"]["step_drift"]), ["rk-baumgarte", "rk-projection"])
        self.assertTrue(any(t.startswith("within the steps:") for t in entry["data"]["legend"]))

    # 7. the stability caption counts the rows drawn, not the method ids
    def test_stability_caption_counts_rows(self):
        entry = self.manifest()["fig_stability_sigma_dt"]
        rows = {r for p in entry["data"]["panels"] for r in p["rows"]}
        self.assertEqual(len(rows), 1)
        self.assertIn("This run: 1 method row (from 3 method ids", entry["caption"])

    # 8. integrators sharing one NLP are told apart; coinciding curves named
    def test_integrators_distinguished_and_coinciding_curves_noted(self):
        from quasiroll_report import figures_methods as fm
        t = np.linspace(0, 1, 50)
        y = 1e-13 * (1 + t)
        self.assertTrue(fm.coinciding((t, y), (t, y * 1.02)))
        self.assertFalse(fm.coinciding((t, y), (t, y * 2)))
        self.assertFalse(fm.coinciding((t, y), (t[:-1], y[:-1])))
        plotting.apply_style()
        fig = plotting.new_figure(5, 3)
        self.addCleanup(plotting.plt.close, fig)
        ax = fig.add_subplot()
        runs = [dict(method="newton/rk-projection/zoh", dae="rk-projection"),
                dict(method="newton/cvode-projection/zoh", dae="cvode-projection")]
        pairs = fm.plot_integrator_curves(ax, [(runs[0], t, y, "a"), (runs[1], t, y, "b")], {})
        self.assertEqual(pairs, [("cvode-projection", "rk-projection")])
        first, second = ax.lines
        self.assertNotEqual(first.get_color(), second.get_color())
        self.assertEqual(first.get_linestyle(), "-")
        self.assertEqual(second.get_linestyle(), "--")
        self.assertIn("colour = integrator", self.manifest()["fig_drift"]["caption"])

    # 9. a failed cell that reached t_end says why; "not run" only when present
    def test_end_of_run_failure_mark_and_not_run_legend(self):
        from quasiroll_report import figures_methods as fm
        late = _base_row(status="drift_exceeded", t_reached=8.0, t_reached_frac=1.0,
                         cause="numerical", cause_detail="baumgarte_instability")
        cell = sel.stability_cell([late])
        self.assertEqual(cell["label"], "1.00·drift")
        self.assertEqual(sel.stability_cell([dict(late, status="gap_exceeded")])["label"],
                         "1.00·gap")
        self.assertEqual(sel.stability_cell([dict(late, t_reached=4.0,
                                                  t_reached_frac=0.5)])["label"], ".50")
        self.assertIn("1.00·drift = reached t_end, but drift_max broke", fm._end_mark_text([cell]))
        self.assertEqual(fm._end_mark_text([sel.stability_cell([_base_row()])]), "")
        full = {"panels": [{"rows": ["m"], "values": [0.1], "cells": {("m", 0): cell}}]}
        gap = {"panels": [{"rows": ["m", "n"], "values": [0.1], "cells": {("m", 0): cell}}]}
        self.assertNotIn("not run", [h.get_label() for h in fm._cause_handles([full])])
        self.assertIn("not run", [h.get_label() for h in fm._cause_handles([gap])])

    # 10. legend labels wrap at '/', ',' or ' ', never inside a token
    def test_legend_wraps_between_tokens(self):
        from quasiroll_report import figures_methods as fm
        from matplotlib.lines import Line2D
        method = "ceres/cvode-projection[jacobian=fd,lmm=bdf,nonlinear_solver=newton]/coupled"
        for width in (40, 32, 26, 20):
            lines = plotting.wrap_label(method, width).split("\n")
            self.assertEqual("".join(lines), method)
            self.assertTrue(all(line[-1] in "/," for line in lines[:-1]), lines)
        self.assertEqual(plotting.wrap_label("non-dominated (beaten by", 16),
                         "non-dominated\n(beaten by")
        plotting.apply_style()
        fig = plotting.new_figure(6, 3)
        self.addCleanup(plotting.plt.close, fig)
        gs = fig.add_gridspec(1, 2, width_ratios=[1, 0.3])
        handles = [Line2D([], [], label=method)]
        fm._legend_axes(fig, gs[0, 1], handles)
        label = handles[0].get_label()
        self.assertIn("\n", label)
        self.assertEqual(label.replace("\n", ""), method)
        self.assertTrue(all(part[-1] in "/," for part in label.split("\n")[:-1]), label)

    # 11. drift vs Δt: a point is one setting's repeats, never an rtol ladder pooled
    def test_drift_vs_dt_point_is_one_setting(self):
        from quasiroll_report import figures_methods as fm

        def row(method, dt, tol, drift, step):
            nlp, dae, coupling = method.split("/")
            return _base_row(run_id=f"{method}-{dt}-{tol}", method=method, nlp=nlp, dae=dae,
                             coupling=coupling, dt=dt, tol=tol, drift_max=drift,
                             drift_step_max=step)
        ladder = "n/cvode-projection/coupled"
        rows = ([row(ladder, dt, 1e-8, 1e-15, 5e-9 * dt / 0.1) for dt in (0.4, 0.2, 0.1)]
                + [row(ladder, 0.1, tol, 1e-13, step) for tol, step in
                   ((1e-3, 4.1e-5), (1e-4, 2.1e-5), (1e-10, 3.7e-11))]
                + [row("n/dp/coupled", 0.1, tol, 1e-12, step) for tol, step in
                   ((1e-3, 4.6e-9), (1e-8, 4.6e-9), (1e-10, 2.9e-11))])
        plotting.apply_style()
        fig = plotting.new_figure(5, 4)
        self.addCleanup(plotting.plt.close, fig)
        ax = fig.add_subplot()
        ctx = types.SimpleNamespace(styles=sel.method_styles(rows))
        drawn, left_out = fm._plot_drift_vs_dt(ax, ctx, {"rows": rows, "label": "p"},
                                               "drift_step_max")
        self.assertEqual((drawn, len(left_out)), (4, 5))
        lines = {len(line.get_xdata()): line for line in ax.lines}
        # the Δt ladder at its own rtol: 5e-9 at Δt 0.1, not the median of 4 rtols
        self.assertEqual(list(lines[3].get_xdata()), [0.1, 0.2, 0.4])
        self.assertAlmostEqual(lines[3].get_ydata()[0], 5e-9)
        # a tolerance ladder at one Δt: its point at the Δt ladders' rtol (1e-8)
        self.assertEqual(list(lines[1].get_ydata()), [4.6e-9])
        text = fm._left_out_rtol_text(left_out)
        self.assertIn("Left out: 5 runs of 2 methods' rtol ladders", text)
        self.assertIn("at other rtols (1.00e-10 to 0.001)", text)
        self.assertIn("their drift within the steps 2.90e-11 to 4.10e-05", text)

    # 12. the front: Pareto dominance with tolerances, ties in error decided by time
    def test_equally_accurate_slow_point_is_not_ringed(self):
        newton = {"err": 4.37e-9, "wall": 0.097, "wall_q1": 0.095, "wall_q3": 0.099}
        ipopt = {"err": 4.34e-9, "wall": 4.91, "wall_q1": 4.8, "wall_q3": 5.0}
        self.assertTrue(sel.dominates(newton, ipopt))      # 0.7 % worse, 50x faster
        self.assertEqual(sel.non_dominated([newton, ipopt]), [newton])
        # more accurate by > 1 % at a time within the spread dominates too
        close = {"err": 4.5e-9, "wall": 0.098, "wall_q1": 0.096, "wall_q3": 0.1}
        self.assertTrue(sel.dominates(newton, close))
        caption = self.manifest()["fig_work_precision"]["caption"]
        self.assertIn("of two points equally accurate within 1 % the slower one", caption)

    def _wp_text(self, rows, estimate, force_rows=None, ref_kind=""):
        from quasiroll_report import figures_methods as fm
        problem = {"label": "p", "groups": ["g"], "ref_err_est": estimate,
                   "ref_kind": ref_kind, "rows": force_rows or rows}
        series = sel.work_precision_series(None, "err_pos_rms", rows=rows)
        points = [p for rungs in series.values() for p in rungs]
        front = sel.non_dominated(points, floor=estimate)
        floor = sel.error_floor(series)
        force_series = sel.work_precision_series(None, "err_force_rms",
                                                 rows=force_rows or rows)
        roundoff = sel.roundoff_floor(16.0)
        stats = fm._force_stats(problem, force_series, roundoff)
        return fm._wp_problem_text(problem, series, front, floor, False,
                                   (16.0, {"run_id": "x"}), stats)

    # 13. the most accurate point and the floor below the reference's estimate
    def test_most_accurate_below_the_estimate_is_not_resolved(self):
        rows = [self._wp_row("a/b/zoh", 0.1, 9.49e-11, 0.0957),
                self._wp_row("c/d/zoh", 0.1, 7.32e-10, 0.5)]
        text = self._wp_text(rows, 6.31e-10)
        self.assertIn("most accurate err_pos_rms 9.49e-11 m in 0.0957 s — below the "
                      "reference's estimated error 6.31e-10 m, not resolved", text)
        self.assertIn("its low end below the reference's estimated error, not resolved",
                      text)
        text = self._wp_text(rows, 1e-11)
        self.assertNotIn("not resolved", text.split("reference error")[0])

    # 14. zero force errors counted; points below the round-off floor; analytic reference
    def test_zero_force_errors_and_analytic_reference_are_stated(self):
        rows = [self._wp_row("a/b/zoh", dt, 1e-3 * dt, 0.1 / dt) for dt in (0.4, 0.2, 0.1)]
        rows[0]["err_force_rms"] = 0.0
        rows[1]["err_force_rms"] = 3e-15
        text = self._wp_text(rows, float("nan"), ref_kind="analytic:circle")
        self.assertIn("1 run with zero force error not drawn on the log axis", text)
        self.assertIn("1 of the force panel's 2 points below it (not resolved)", text)
        self.assertIn("the reference is analytic (ref_kind analytic:circle)", text)
        self.assertNotIn("not estimated", text)
        self.assertIn("reference error not estimated", self._wp_text(rows, float("nan")))

    # 15. a line joining a Δt and an rtol ladder labels its points with both
    def test_joined_ladders_label_dt_and_rtol(self):
        rows = ([self._wp_row("a/b/coupled", dt, 1e-3 * dt, 1.0 / dt, tol=1e-8)
                 for dt in (0.4, 0.2)]
                + [self._wp_row("a/b/coupled", 0.1, 1e-3 * tol, 1.0 / tol ** 0.1, tol=tol)
                   for tol in (1e-3, 1e-6, 1e-8)])
        labels = [p["label"] for p in sel.work_precision_series(
            None, "err_pos_rms", rows=rows)["a/b/coupled"]]
        self.assertEqual(labels, ["0.4/1e-8", "0.2/1e-8", "0.1/1e-3", "0.1/1e-6",
                                  "0.1/1e-8"])
        # Δt and rtol stepped together: the Δt alone tells the points apart
        rows = [self._wp_row("a/b/coupled", dt, 1e-3 * dt, 1.0 / dt, tol=dt * 1e-3)
                for dt in (0.2, 0.1, 0.05)]
        self.assertEqual([p["label"] for p in sel.work_precision_series(
            None, "err_pos_rms", rows=rows)["a/b/coupled"]], ["0.2", "0.1", "0.05"])
        self.assertEqual(sel.rung_label(0.1, 1e-6, True), "1e-6")
        self.assertEqual(sel.rung_label(0.1, 1e-6, False), "0.1")

    # 16. a flat or negative zoh fit is no order: rtol-limited
    def test_flat_zoh_fit_reads_rtol_limited(self):
        from quasiroll_report import figures_methods as fm

        def line(errs, dae, method):
            return [{"dt": dt, "tol": 1e-8, "err": e, "coupling": "zoh", "dae": dae,
                     "run": _base_row(dae=dae, method=method)}
                    for dt, e in zip((0.4, 0.2, 0.1, 0.05), errs)]
        series = {"n/cvode-projection/zoh": line([1.9e-9, 6.8e-9, 1.5e-8, 2.9e-8],
                                                 "cvode-projection", "n/cvode-projection/zoh"),
                  "n/ida/zoh": line([2.2e-9, 1.8e-8, 1.9e-8, 2.2e-9], "ida", "n/ida/zoh"),
                  "n/rk-projection/zoh": line([7.8e-10, 5.1e-11, 3.2e-12, 2.0e-13],
                                              "rk-projection", "n/rk-projection/zoh")}
        text = fm._hold_order_text([({"label": "C"}, series)])
        self.assertIn("cvode-projection rtol-limited (no Δt order)", text)
        self.assertIn("ida rtol-limited (no Δt order)", text)
        self.assertIn("rk-projection 4.0", text)
        self.assertNotIn("-1.3", text)
        self.assertEqual(sel.order_text(0.1, False), "flat (no Δt order)")

    # 17. the stability chart's μ_min(ref) names its horizon
    def test_stability_mu_min_names_its_horizon(self):
        from quasiroll_report import figures_methods as fm
        rows = [_base_row(run_id=f"s{k}", suite_group="stability_mu", scene="paper_pvc",
                          mu=mu, t_end=6.0, ref_mu_min=0.115, ref_status="success")
                for k, mu in enumerate((0.1, 0.2, 0.5))]
        panel, = sel.stability_charts(rows)[0]["panels"]
        self.assertEqual(panel["mu_min_horizon"], 6.0)
        plotting.apply_style()
        fig = plotting.new_figure(6, 2)
        self.addCleanup(plotting.plt.close, fig)
        ax = fig.add_subplot()
        fm._draw_stability_panel(ax, panel, "μ [-]", "mu")
        fig.canvas.draw()
        top = [t.get_text() for child in ax.child_axes for t in child.get_xticklabels()]
        self.assertIn("μ_min(ref) = 0.115 over 0–6 s", top)
        caption = self.manifest()["fig_stability_mu"]["caption"]
        self.assertRegex(caption, r"μ_min\(ref\) [0-9.]+ over 0–[0-9.]+ s")

    # 18. an rtol axis says where one step per output sample makes rtol moot
    def test_stability_tol_names_step_capped_rows(self):
        from quasiroll_report import figures_methods as fm

        def row(nlp, tol, steps, err):
            return _base_row(run_id=f"{nlp}{tol}", suite_group="stability_tol", nlp=nlp,
                             dae="rk-baumgarte", method=f"{nlp}/rk-baumgarte[rk_method=dp54]"
                             "/coupled", coupling="coupled", dt=0.1, tol=tol, steps=steps,
                             t_reached=4.0, t_end=4.0, err_pos_rms=err)
        rows = [row(nlp, tol, steps, err) for nlp in ("ceres", "newton")
                for tol, steps, err in ((1e-3, 44, 3.5684e-8), (1e-6, 44, 3.5684e-8),
                                        (1e-9, 91, 7e-10))]
        ctx = types.SimpleNamespace(runs=rows)
        text = fm._tol_plateau_text(ctx, {"axis": "tol", "group": "stability_tol"})
        self.assertIn("rk-baumgarte[rk_method=dp54]/coupled with ceres, newton (rtol 0.001 "
                      "to 1.00e-06 at Δt = 0.1 s)", text)
        self.assertIn("rtol changes neither the steps nor the outcome", text)
        self.assertEqual(fm._tol_plateau_text(ctx, {"axis": "mu", "group": "stability_tol"}),
                         "")

    # 19. Fig. 15: the ratio's Δt stated; drift_step_max a mark at the right edge
    def test_stabilisation_ratio_dt_and_step_marks(self):
        from quasiroll_report import figures_methods as fm
        t = np.linspace(0.0, 20.0, 41)
        base = _base_row(dae="rk-baumgarte", dt=0.025, drift_step_max=8.79e-10)
        proj = _base_row(dae="cvode-projection", dt=0.05, drift_step_max=3.53e-7)
        drift = np.full(41, 1e-13)
        entries = [(base, t, drift, 1.0), (proj, t, drift, 1.0)]
        text = fm._stabilisation_text(entries)
        self.assertIn("(cvode-projection 402× rk-baumgarte, cvode-projection at Δt = 0.05 s, "
                      "rk-baumgarte at Δt = 0.025 s)", text)
        proj["dt"] = 0.025
        self.assertIn("402× rk-baumgarte, both at Δt = 0.025 s)",
                      fm._stabilisation_text(entries))
        plotting.apply_style()
        fig = plotting.new_figure(6, 3)
        self.addCleanup(plotting.plt.close, fig)
        ax = fig.add_subplot()
        ax.plot(t, drift)
        fm._mark_step_drift(ax, [base, proj])
        marks = [line for line in ax.lines if line.get_label().startswith("within the steps")]
        self.assertEqual(len(marks), 2)
        for mark in marks:
            self.assertEqual(list(mark.get_xdata()), [1.0 - fm.STEP_MARK_SHARE, 1.0])
        self.assertIn("short marks (◄) at the right edge",
                      self.manifest()["fig15_stabilisation"]["caption"])

    # 20. every value column keeps a tick label: a crowded one on a second line
    def test_crowded_value_ticks_keep_their_labels(self):
        from quasiroll_report import figures_methods as fm
        rows = ["n/rk-baumgarte/zoh"]
        panel = {"rows": rows, "values": [1.0, 2.5, 3.0, 10.0], "numeric": True, "log": True,
                 "cells": {(rows[0], j): {"cls": "success", "detail": "", "label": "1"}
                           for j in range(4)},
                 "label": "x", "mu_min": float("nan"), "limits": [(2.785, 1)],
                 "limit_rows": {1: rows}}
        plotting.apply_style()
        fig = plotting.new_figure(4.5, 1.6)
        self.addCleanup(plotting.plt.close, fig)
        ax = fig.add_subplot()
        fm._draw_stability_panel(ax, panel, "σ·Δt [-]", "sigma_dt")
        # the crowded 3 on a second line below 2.5
        self.assertEqual([t.get_text() for t in ax.get_xticklabels()],
                         ["1", "2.5", "\n3", "10"])
        self.assertEqual(fm.value_tick_layout([0, 10, 15, 30]), [False, True, None, False])
        self.assertEqual(fm.value_tick_layout([0, 17], rotated=True), [False, None])


if __name__ == "__main__":
    sys.exit(main())


def _point(err, wall, iqr=0.0, label="", method="m"):
    return {"err": err, "wall": wall, "wall_q1": wall - iqr / 2, "wall_q3": wall + iqr / 2,
            "label": label, "method": method, "exclusive": True}


class WorkPrecisionRulesTest(unittest.TestCase):
    def test_step_cap_plateau_is_named(self):
        """An rtol ladder flat because one step is taken per output interval
        is named as such; a ladder whose error falls is not."""
        from quasiroll_report import figures_methods

        def rung(method, tol, err, steps):
            return {"method": method, "tol": tol, "err_pos_rms": err, "steps": steps,
                    "dt": 0.1, "t_reached": 20.0, "t_end": 20.0, "substeps": 1}
        rows = [rung("capped", 1e-3, 6.6e-8, 244), rung("capped", 1e-4, 6.6e-8, 244),
                rung("capped", 1e-5, 6.59e-8, 245), rung("capped", 1e-8, 3e-9, 656),
                rung("falls", 1e-3, 5e-5, 211), rung("falls", 1e-4, 2e-5, 585)]
        text = figures_methods._step_cap_text(rows)
        self.assertIn("capped (rtol 0.001 to 1.00e-05 at Δt = 0.1 s)", text)
        self.assertNotIn("falls", text)
        self.assertEqual(figures_methods._step_cap_text(rows[4:]), "")

    """The dominance rule and the recommendation table (issue 21 item 7), on
    hand-made points whose verdicts follow from the rule's two thresholds."""

    def test_tie_in_error_slower_is_dominated(self):
        # 1.6x slower and only 2e-6 relative error apart: equally accurate
        # within 1 %, so the faster one dominates (Pareto with tolerances).
        fast, slow = _point(1.0e-4, 1.0), _point(1.0e-4 * (1 + 2e-6), 1.6)
        self.assertTrue(sel.dominates(fast, slow))
        self.assertEqual(sel.non_dominated([fast, slow]), [fast])
        # within both tolerances of each other: neither dominates
        twin = _point(1.0e-4 * 1.005, 1.05, iqr=0.2)
        self.assertFalse(sel.dominates(fast, twin))
        self.assertFalse(sel.dominates(twin, fast))

    def test_timing_within_iqr_ranks_by_error(self):
        # 10x the error and 0.05 s slower with an IQR of 0.1 s: the times are
        # indistinguishable, the error is not, so b dominates a ...
        a, b = _point(1e-3, 1.05, iqr=0.1), _point(1e-4, 1.0, iqr=0.02)
        self.assertTrue(sel.dominates(b, a))
        # ... also when b is the slower one within the spread
        self.assertTrue(sel.dominates(_point(1e-4, 1.08, iqr=0.1), a))
        # but not when b is slower beyond it
        self.assertFalse(sel.dominates(_point(1e-4, 1.3, iqr=0.1), a))

    def test_worse_beyond_either_threshold_is_dominated(self):
        best = _point(1e-5, 1.0, iqr=0.1)
        worse = _point(1e-5 * 1.02, 1.2, iqr=0.1)   # +2 % error, +0.2 s > IQR
        edge = _point(1e-5 * 1.009, 1.5, iqr=0.1)   # +0.9 % error, slower
        fast = _point(1e-5 * 1.5, 0.5, iqr=0.1)     # worse but faster
        front = sel.non_dominated([best, worse, edge, fast])
        self.assertIn(best, front)
        self.assertNotIn(worse, front)
        self.assertNotIn(edge, front)
        self.assertIn(fast, front)

    def test_error_floor_spread_of_best_tightest_rungs(self):
        series = {"a": [_point(1e-2, 1), _point(1e-6, 4)],
                  "b": [_point(1e-3, 1), _point(4e-6, 3)],
                  "c": [_point(1e-2, 1), _point(1e-3, 2)]}   # 1000x above: not best
        low, high, lines = sel.error_floor(series)
        self.assertEqual((low, high), (1e-6, 4e-6))
        self.assertEqual(lines, ["a", "b"])

    def test_recommendation_fastest_per_decade_with_ties(self):
        series = {
            "slow/accurate": [_point(3e-3, 2.0, 0.1, "0.4"), _point(2e-6, 8.0, 0.4, "0.1")],
            "fast/coarse": [_point(5e-3, 0.5, 0.05, "0.2"), _point(6e-4, 1.0, 0.05, "0.05")],
            "twin": [_point(8e-4, 1.04, 0.2, "0.05")],
        }
        points = [p for rungs in series.values() for p in rungs]
        low, high, _ = sel.error_floor(series)
        targets = sel.recommendation_targets(points, low)
        # decades from above the largest error (5e-3 -> 1e-2) to the floor (2e-6 -> 1e-6)
        self.assertEqual(targets, [1e-2, 1e-3, 1e-4, 1e-5, 1e-6])
        recs = {r["target"]: r for r in sel.recommendations(series, targets)}
        self.assertEqual(recs[1e-2]["line"], "fast/coarse")
        self.assertEqual(recs[1e-2]["winner"]["label"], "0.2")
        self.assertEqual(recs[1e-3]["line"], "fast/coarse")
        self.assertEqual(recs[1e-3]["winner"]["wall"], 1.0)
        # twin is 0.04 s slower, within the larger IQR (0.2 s): indistinguishable
        self.assertEqual(recs[1e-3]["ties"], ["twin"])
        self.assertAlmostEqual(recs[1e-3]["iqr"], 0.05)
        self.assertEqual(recs[1e-4]["line"], "slow/accurate")
        self.assertEqual(recs[1e-4]["ties"], [])
        self.assertIsNone(recs[1e-6]["winner"])

    def test_rung_labels(self):
        self.assertEqual(sel.rung_label(0.1, 1e-6, True), "1e-6")
        self.assertEqual(sel.rung_label(0.05, 1e-8, False), "0.05")

    def test_quartiles_from_repeats_match_harness_definition(self):
        run = {"wall_s_median": 0.3, "wall_s": 0.1, "timings": [0.5, 0.1, 0.4, 0.2, 0.3]}
        self.assertEqual(sel.timing_quartiles(run), (0.3, 0.2, 0.4))
        run.update({"wall_s_q1": 0.25, "wall_s_q3": 0.35})
        self.assertEqual(sel.timing_quartiles(run), (0.3, 0.25, 0.35))
