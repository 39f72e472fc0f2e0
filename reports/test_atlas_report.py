#!/usr/bin/python3
"""Tests of the atlas page (reports/quasiroll_report/atlas.py) on a small
synthetic atlas.csv: /usr/bin/python3 reports/test_atlas_report.py"""

import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

from quasiroll_report import atlas, atlas_view  # noqa: E402

HEADER = ["cell", "x", "y", "heading", "mode", "status", "detail", "mu_min",
          "critical_wheel", "mu", "margin", "min_normal_force", "z", "roll",
          "pitch", "wall_s"]


def write_atlas(directory):
    """3 x 2 positions, 2 headings, both modes; one pose cannot stand."""
    rows, cell = [], 0
    for x in (0.0, 1.0, 2.0):
        for y in (0.0, 1.0):
            for h in (0.0, 3.141592653589793):
                for mode in ("paper", "pvc"):
                    mu_min = 0.1 * (1 + x) * (2 if mode == "pvc" else 1)
                    status, wheel = "ok", 1 + cell % 3
                    if x == 2.0 and y == 1.0 and mode == "pvc" and h == 0.0:
                        status, mu_min, wheel = "no_contact", float("nan"), 0
                    rows.append([cell, x, y, h, mode, status,
                                 "" if status == "ok" else "stalled", mu_min,
                                 wheel, 0.5, 0.5 - mu_min, 10.0, 0.1, 0.0,
                                 0.0, 0.001])
                    cell += 1
    with open(os.path.join(directory, "atlas.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        w.writerows(rows)
    with open(os.path.join(directory, "meta.json"), "w") as f:
        json.dump({"kind": "atlas", "key": "atlas{test}", "commit": "abc"}, f)
    with open(os.path.join(directory, "edge.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["cell", "mode", "backend", "offset", "mu", "verdict",
                    "qs_status", "nlp_status", "iterations", "kkt_residual",
                    "wall_s"])
        w.writerow([0, "paper", "fake", 0.01, 0.101, "correct", "OK",
                    "converged", 5, 1e-13, 0.002])
        w.writerow([0, "paper", "fake", -0.01, 0.099, "wrong_claim", "OK",
                    "converged", 7, 1e-13, 0.004])
        w.writerow([0, "paper", "fake", -0.001, 0.0999, "correct",
                    "INFEASIBLE_FRICTION", "infeasible", 9, "nan", 0.006])
    with open(os.path.join(directory, "terrain.json"), "w") as f:
        json.dump({"type": "gaussians", "bumps": [[0.05, 1.0, 0.5, 0.4]]}, f)


class AtlasReport(unittest.TestCase):
    def test_page_has_every_figure_and_the_causes(self):
        with tempfile.TemporaryDirectory() as d:
            write_atlas(d)
            out = subprocess.run([sys.executable, os.path.join(HERE, "make_report.py"), d],
                                 capture_output=True, text=True, check=True)
            index = out.stdout.strip().splitlines()[-1]
            page = open(index, encoding="utf-8").read()
            for name in ("atlas_mu_min", "atlas_pvc_gain", "atlas_fraction",
                         "atlas_wheel", "atlas_edge"):
                self.assertIn(f"{name}.png", page)
                self.assertTrue(os.path.isfile(os.path.join(d, "report", f"{name}.svg")))
            self.assertIn("no_contact", page)
            self.assertIn("atlas{test}", page)
            self.assertIn("Solver reliability at the edge", page)
            # The edge chart counts the wrong claim in its caption.
            self.assertIn("converged below the edge: 1 in total", page)

    def test_edge_summary_counts_wrong_claims(self):
        with tempfile.TemporaryDirectory() as d:
            write_atlas(d)
            with open(os.path.join(d, "edge.csv"), newline="") as f:
                rows = list(csv.DictReader(f))
        above, below = sorted(atlas.edge_summary(rows), key=lambda s: s["side"])
        self.assertEqual(above["counts"]["correct"], 1)
        self.assertEqual(below["counts"]["wrong_claim"], 1)
        self.assertEqual(below["counts"]["correct"], 1)
        self.assertEqual(below["detected"], 1)
        self.assertEqual(below["median_iterations"], 9)

    def test_grid_and_fraction(self):
        with tempfile.TemporaryDirectory() as d:
            write_atlas(d)
            grid = atlas.Grid(atlas._read_atlas(d))
        self.assertEqual(grid.modes, ["paper", "pvc"])
        self.assertEqual(grid.mu_min.shape, (2, 2, 2, 3))
        self.assertEqual(int((~grid.standing).sum()), 1)
        # pvc at mu = 0.45: mu_min 0.2, 0.4 (x = 0, 1) pass, 0.6 (x = 2) not,
        # and the pose that cannot stand counts as not traversable.
        self.assertAlmostEqual(atlas.traversable_fraction(grid.mu_min[1], 0.45), 8 / 12)
        self.assertAlmostEqual(atlas.traversable_fraction(grid.mu_min[0], 0.45), 1.0)
        # The minimum over headings skips the heading where it cannot stand.
        best = grid.min_over_headings(1)
        self.assertAlmostEqual(best[1, 2], 0.6)


if __name__ == "__main__":
    unittest.main()

class AtlasView(unittest.TestCase):
    def test_view_data_has_every_heading_and_the_minimum(self):
        with tempfile.TemporaryDirectory() as d:
            write_atlas(d)
            grid = atlas.Grid(atlas._read_atlas(d))
        data = atlas_view.atlas_view_data(grid, {"type": "gaussians",
                                                 "bumps": [[0.05, 1.0, 0.5, 0.4]]})
        self.assertEqual(sorted(data["maps"]), ["paper", "pvc", "pvc - paper"])
        nh = len(grid.headings)
        self.assertEqual(len(data["maps"]["paper"]), nh + 1)
        self.assertEqual(len(data["heights"]), len(grid.ys))
        self.assertEqual(len(data["heights"][0]), len(grid.xs))
        # The pose where pvc cannot stand (x = 2, y = 1, heading 0) is None.
        ix, iy = grid.xs.index(2.0), grid.ys.index(1.0)
        self.assertIsNone(data["maps"]["pvc"][0][iy][ix])
        # The last layer is the minimum over the headings.
        paper = data["maps"]["paper"]
        for j in range(len(grid.ys)):
            for i in range(len(grid.xs)):
                values = [paper[h][j][i] for h in range(nh) if paper[h][j][i] is not None]
                self.assertAlmostEqual(paper[nh][j][i], min(values))
        self.assertGreaterEqual(data["vmax"], 1.2 * 0.5)

    @unittest.skipUnless(shutil.which("chromium") and atlas_view.find_three(),
                         "needs chromium and libjs-three")
    def test_page_renders_in_headless_chromium(self):
        with tempfile.TemporaryDirectory() as d:
            write_atlas(d)
            subprocess.run([sys.executable, os.path.join(HERE, "make_report.py"), d],
                           capture_output=True, text=True, check=True)
            page = os.path.join(d, "report", "atlas3d", "index.html")
            dom = subprocess.run(
                ["chromium", "--headless", "--no-sandbox", "--use-angle=swiftshader",
                 "--enable-unsafe-swiftshader", "--no-first-run",
                 f"--user-data-dir={d}/profile", "--virtual-time-budget=10000",
                 "--dump-dom", f"file://{page}?mode=pvc&heading=1"],
                capture_output=True, text=True, timeout=120).stdout
        self.assertIn('<body data-ready="1"', dom)
        self.assertIn("modes: paper, pvc, pvc - paper", dom)

