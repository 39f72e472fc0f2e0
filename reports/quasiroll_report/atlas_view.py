"""The atlas's 3D view: OUT/atlas3d/index.html, the terrain of an atlas
coloured by mu_min, with a heading slider (the headings of the grid and,
last, the minimum over them), a mode selector (paper, pvc, pvc - paper) and
the scene's mu marked. Like the run replay (replay.py) it is a self-contained
page with Debian's three.js copied beside it, so it opens from file://.

The mesh has a vertex per grid position (x, y) at the terrain's height there
(terrain.json); its colour is the cell's value on a viridis scale from 0 to
`vmax` (shown in the key), grey where the robot cannot stand. With "mark
mu_min > mu" the poses the scene's mu does not carry are drawn red.
`?mode=pvc&heading=K` opens that view; the page sets
`<body data-ready="1">` once it has rendered.
"""

import json
import math
import os
import shutil

import numpy as np
from matplotlib import colormaps

from .replay import THREE_FILES, find_three, viewer_page
from .terrain import terrain_height


def _values(array):
    """A 2-D array as rows of numbers, None where not finite."""
    return [[round(float(v), 6) if math.isfinite(v) else None for v in row]
            for row in array]


def atlas_view_data(grid, terrain):
    """The page's data: grid axes, heights, and per mode the mu_min maps for
    every heading plus the minimum over headings."""
    xx, yy = np.meshgrid(grid.xs, grid.ys)
    heights = np.zeros_like(xx)
    if terrain is not None:
        try:
            heights = terrain_height(terrain, xx, yy)
        except (KeyError, ValueError, TypeError):
            heights = np.zeros_like(xx)
    maps = {}
    for m, mode in enumerate(grid.modes):
        layers = [np.where(grid.standing[m, h], grid.mu_min[m, h], np.nan)
                  for h in range(len(grid.headings))]
        best = grid.min_over_headings(m)
        layers.append(np.where(np.isfinite(best), best, np.nan))
        maps[mode] = [_values(layer) for layer in layers]
    if "paper" in maps and "pvc" in maps:
        paper = grid.min_over_headings(grid.modes.index("paper"))
        pvc = grid.min_over_headings(grid.modes.index("pvc"))
        with np.errstate(invalid="ignore"):
            gain = np.where(np.isfinite(paper) & np.isfinite(pvc), pvc - paper, np.nan)
        maps["pvc - paper"] = [_values(gain)]
    finite = [v for layers in maps.values() for layer in layers for row in layer
              for v in row if v is not None]
    vmax = float(np.percentile(finite, 98)) if finite else 1.0
    if math.isfinite(grid.mu):
        vmax = max(vmax, 1.2 * grid.mu)
    lut = colormaps["viridis"](np.linspace(0, 1, 64))[:, :3]
    return {"xs": [float(v) for v in grid.xs], "ys": [float(v) for v in grid.ys],
            "heights": _values(heights),
            "headings_deg": [round(math.degrees(h), 3) for h in grid.headings],
            "mu": grid.mu if math.isfinite(grid.mu) else None,
            "maps": maps, "vmax": round(vmax, 6),
            "lut": [[round(float(c), 4) for c in rgb] for rgb in lut]}


def write_atlas_view(grid, terrain, out_dir):
    """Write OUT/atlas3d/; return (html snippet, notes)."""
    three = find_three()
    if three is None:
        return "", ["3D view omitted: three.js (Debian package libjs-three) is not "
                    "installed in /usr/share/javascript/three"]
    if len(grid.xs) < 2 or len(grid.ys) < 2:
        return "", ["3D view omitted: the grid has a single x or y"]
    folder = os.path.join(out_dir, "atlas3d")
    os.makedirs(folder, exist_ok=True)
    for src, dst in THREE_FILES:
        shutil.copyfile(os.path.join(three, src), os.path.join(folder, dst))
    with open(os.path.join(folder, "data.js"), "w", encoding="utf-8") as handle:
        handle.write("window.QUASIROLL_ATLAS = ")
        json.dump(atlas_view_data(grid, terrain), handle, separators=(",", ":"),
                  allow_nan=False)
        handle.write(";\n")
    with open(os.path.join(folder, "index.html"), "w", encoding="utf-8") as handle:
        handle.write(viewer_page(VIEWER_HTML, "QUASIROLL_ATLAS"))
    snippet = (
        "<h2>3D view</h2><p>The terrain coloured by mu_min (viridis, 0 to the key's "
        "maximum; grey: the robot cannot stand there), one heading at a time with "
        "the slider (its last position: the minimum over all headings), paper or "
        "pvc mode or their difference; tick the box to draw in red the poses the "
        "scene's μ does not carry. Drag to orbit, wheel to zoom; "
        "<code>?mode=pvc&amp;heading=K</code> opens a view. "
        '<a href="atlas3d/index.html">Open full page</a>.</p>'
        '<iframe src="atlas3d/index.html" title="atlas 3D view" '
        'style="width:100%;height:560px;border:1px solid #ccc"></iframe>')
    return snippet, []


VIEWER_HTML = r"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>quasiroll atlas 3D view</title>
<style>
html, body { margin: 0; height: 100%; overflow: hidden; font-family: sans-serif; }
#view { position: absolute; top: 0; left: 0; right: 0; bottom: 56px; }
#bar { position: absolute; left: 0; right: 0; bottom: 0; height: 56px;
       background: #f4f4f4; border-top: 1px solid #ccc; padding: 4px 10px;
       box-sizing: border-box; font-size: 13px; }
#bar input[type=range] { width: 40%; vertical-align: middle; }
#key { position: absolute; top: 6px; right: 6px; background: rgba(255,255,255,0.9);
       font-size: 12px; padding: 4px 6px; border: 1px solid #ccc; }
#ramp { width: 160px; height: 12px; display: block; margin: 2px 0; }
</style>
@PAGE_START@
<div id="key"><span id="what"></span><canvas id="ramp" width="160" height="12"></canvas>
<span id="range"></span></div>
<div id="bar">
  <select id="mode"></select>
  heading <input id="heading" type="range" min="0" max="0" value="0">
  <span id="label"></span>
  <label><input id="mark" type="checkbox"> mark mu_min &gt; μ</label><br>
  <span id="status">loading</span>
</div>
<script>
(function () {
@BOOT@
  var d = window.QUASIROLL_ATLAS, nx = d.xs.length, ny = d.ys.length;
  var view = document.getElementById("view");
  view.appendChild(renderer.domElement);
  var scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  scene.add(new THREE.AmbientLight(0xffffff, 0.7));
  var sun = new THREE.DirectionalLight(0xffffff, 0.45);
  sun.position.set(-1, -2, 4);
  scene.add(sun);
  var camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
  camera.up.set(0, 0, 1);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);

  // Heights exaggerated so that bumps of a few cm show on a grid of metres.
  var span = Math.max(d.xs[nx - 1] - d.xs[0], d.ys[ny - 1] - d.ys[0]);
  var lo = Infinity, hi = -Infinity;
  d.heights.forEach(function (row) { row.forEach(function (h) {
    lo = Math.min(lo, h); hi = Math.max(hi, h); }); });
  var exaggerate = hi > lo ? Math.max(1, 0.15 * span / (hi - lo)) : 1;
  var pos = [], idx = [];
  for (var j = 0; j < ny; j++)
    for (var i = 0; i < nx; i++)
      pos.push(d.xs[i], d.ys[j], (d.heights[j][i] - lo) * exaggerate);
  for (j = 0; j + 1 < ny; j++)
    for (i = 0; i + 1 < nx; i++) {
      var a = j * nx + i;
      idx.push(a, a + 1, a + nx, a + 1, a + nx + 1, a + nx);
    }
  var geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.Float32BufferAttribute(pos, 3));
  var colours = new Float32Array(nx * ny * 3);
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  geometry.setIndex(idx);
  geometry.computeVertexNormals();
  scene.add(new THREE.Mesh(geometry, new THREE.MeshLambertMaterial(
    {vertexColors: THREE.VertexColors, side: THREE.DoubleSide})));

  var modeSel = document.getElementById("mode"), slider = document.getElementById("heading");
  var mark = document.getElementById("mark"), label = document.getElementById("label");
  Object.keys(d.maps).forEach(function (m) {
    var o = document.createElement("option");
    o.value = m; o.textContent = m;
    modeSel.appendChild(o);
  });
  var params = new URLSearchParams(window.location.search);
  if (params.get("mode") && d.maps[params.get("mode")]) modeSel.value = params.get("mode");

  function colourOf(v, signed) {
    if (v === null) return [0.74, 0.74, 0.74];
    var s = signed ? 0.5 + 0.5 * v / d.vmax : v / d.vmax;
    s = Math.max(0, Math.min(1, s));
    return d.lut[Math.round(s * (d.lut.length - 1))];
  }
  function drawRamp(signed) {
    var c = document.getElementById("ramp").getContext("2d");
    for (var k = 0; k < 160; k++) {
      var rgb = d.lut[Math.round(k / 159 * (d.lut.length - 1))];
      c.fillStyle = "rgb(" + rgb.map(function (v) { return Math.round(255 * v); }) + ")";
      c.fillRect(k, 0, 1, 12);
    }
    document.getElementById("range").textContent = signed
      ? (-d.vmax).toFixed(3) + " … 0 … +" + d.vmax.toFixed(3)
      : "0 … " + d.vmax.toFixed(3) + (d.mu !== null ? "  (scene μ = " + d.mu + ")" : "");
  }
  function update() {
    var layers = d.maps[modeSel.value], signed = modeSel.value === "pvc - paper";
    slider.max = layers.length - 1;
    var h = Math.min(+slider.value, layers.length - 1);
    var layer = layers[h];
    var last = h === layers.length - 1;
    label.textContent = signed ? "minimum over headings (pvc − paper)"
      : last ? "minimum over headings" : d.headings_deg[h] + "°";
    document.getElementById("what").textContent = signed ? "Δ mu_min" : "mu_min";
    for (var j = 0; j < ny; j++)
      for (var i = 0; i < nx; i++) {
        var v = layer[j][i], rgb = colourOf(v, signed);
        if (!signed && mark.checked && v !== null && d.mu !== null && v > d.mu)
          rgb = [0.84, 0.15, 0.16];
        colours.set(rgb, 3 * (j * nx + i));
      }
    geometry.attributes.color.needsUpdate = true;
    drawRamp(signed);
    render();
  }
  function render() {
    var w = view.clientWidth || 800, hgt = view.clientHeight || 500;
    renderer.setSize(w, hgt);
    camera.aspect = w / hgt;
    camera.updateProjectionMatrix();
    renderer.render(scene, camera);
  }
  var cx = 0.5 * (d.xs[0] + d.xs[nx - 1]), cy = 0.5 * (d.ys[0] + d.ys[ny - 1]);
  controls.target.set(cx, cy, 0);
  camera.position.set(cx - 0.2 * span, cy - 1.1 * span, 0.9 * span);
  controls.update();
  controls.addEventListener("change", render);
  window.addEventListener("resize", render);
  [modeSel, slider, mark].forEach(function (el) {
    el.addEventListener(el === slider ? "input" : "change", update);
  });
  slider.max = d.maps[modeSel.value].length - 1;
  if (params.get("heading") !== null) slider.value = params.get("heading");
  update();
  status.textContent = nx + " x " + ny + " positions, " + d.headings_deg.length +
    " headings, modes: " + Object.keys(d.maps).join(", ") + "; heights x" +
    exaggerate.toFixed(1);
  body.setAttribute("data-ready", "1");
})();
</script>
</body></html>
"""
