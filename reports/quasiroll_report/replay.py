"""The 3D replay: a self-contained page (replay/index.html) with three.js from
Debian's libjs-three copied beside it, so it works from file:// offline.

The Python side does the kinematics (robot.py: platform pose, wheel frames
with steer and camber, contact forces in world coordinates); the page only
places meshes with the precomputed matrices. The page sets
`<body data-ready="1">` once the first frame is rendered ("error" and a
message when WebGL is unavailable); `?run=<run_id>` (or an index) selects
the run, `?frame=K` opens frame K, `?norobot=1` hides the robot (the
screenshot test's negative control). Besides the robot the page shows x/y/z
axes with a scale bar, a force scale (a reference arrow of FORCE_BAR N),
the per-frame values (t, speeds, wheel forces, camber) and the friction cone
|t| <= μ N at each contact, drawn to the force arrows' scale.
"""

import json
import math
import os
import shutil

import numpy as np

from . import robot
from .problems import robot_geometry, scene_mode
from .terrain import terrain_height

THREE_DIRS = ["/usr/share/javascript/three"]
THREE_FILES = [("three.min.js", "three.min.js"),
               ("examples/js/controls/OrbitControls.js", "OrbitControls.js")]
MAX_FRAMES = 400
CHASSIS_HEX = "#ff00ff"  # unlit magenta: the screenshot test looks for it


def find_three():
    """Directory of Debian's libjs-three with every file the page needs, or None."""
    for folder in THREE_DIRS:
        if all(os.path.isfile(os.path.join(folder, src)) for src, _ in THREE_FILES):
            return folder
    return None


def _round(values, digits=6):
    return [round(float(v), digits) for v in values]


def _terrain_mesh(spec, traj, margin=0.45, n=64):
    xs = np.concatenate([traj[f"c{i}_x"] for i in (1, 2, 3)] + [traj["x"]])
    ys = np.concatenate([traj[f"c{i}_y"] for i in (1, 2, 3)] + [traj["y"]])
    xs, ys = xs[np.isfinite(xs)], ys[np.isfinite(ys)]
    box = [float(xs.min() - margin), float(xs.max() + margin),
           float(ys.min() - margin), float(ys.max() + margin)]
    gx, gy = np.meshgrid(np.linspace(box[0], box[1], n), np.linspace(box[2], box[3], n))
    if spec is not None:
        heights = terrain_height(spec, gx, gy)
    else:  # no terrain file: a plane through the lowest contact point
        zs = np.concatenate([traj[f"c{i}_z"] for i in (1, 2, 3)])
        heights = np.full_like(gx, float(np.nanmin(zs)))
    return {"box": box, "n": n, "heights": _round(heights.ravel(), 5)}


def nice_length(value):
    """The largest of 1, 2, 2.5, 5 x 10^k not above value (scale bars)."""
    if not (value > 0 and math.isfinite(value)):
        return 1.0
    power = 10.0 ** math.floor(math.log10(value))
    return max(m * power for m in (1.0, 2.0, 2.5, 5.0) if m * power <= value * (1 + 1e-12))


def _finite(value):
    value = float(value)
    return round(value, 6) if math.isfinite(value) else None


def _normal(spec, x, y):
    if spec is None:
        return np.array([0.0, 0.0, 1.0])
    return robot.terrain_normal(spec, x, y, terrain_height)


def replay_data(ctx, run):
    """Everything the page draws for one run (JSON-able)."""
    traj = ctx.trajectories.get(run)
    geom = robot_geometry(ctx.references.get(run.get("ref_hash", "")))
    spec = ctx.terrain_of(run)
    rows = [k for k in range(len(traj["t"])) if robot.finite_pose(robot.row_at(traj, k))]
    if len(rows) > MAX_FRAMES:
        rows = [rows[int(round(i))] for i in np.linspace(0, len(rows) - 1, MAX_FRAMES)]
    weight = None
    frames = []
    for k in rows:
        row = robot.row_at(traj, k)
        rot, pos = robot.platform_pose(row)
        wheels, contacts, forces, normals = [], [], [], []
        for i, (rot_w, centre) in enumerate(robot.wheel_frames_world(geom, row), start=1):
            wheels.append(_round(list(rot_w.ravel()) + list(centre)))
            point = np.array([row[f"c{i}_x"], row[f"c{i}_y"], row[f"c{i}_z"]])
            contacts.append(_round(point))
            n_force = row.get(f"n{i}", math.nan)
            if all(math.isfinite(row.get(c, math.nan)) for c in
                   (f"n{i}", f"t{i}_lon", f"t{i}_lat")):
                force = robot.contact_force_world(rot_w, _normal(spec, point[0], point[1]),
                                                  n_force, row[f"t{i}_lon"], row[f"t{i}_lat"])
            else:
                force = np.zeros(3)
            forces.append(_round(force, 4))
            normal = _normal(spec, point[0], point[1]) if np.all(np.isfinite(point)) \
                else np.array([0.0, 0.0, 1.0])
            normals.append(_round(normal / np.linalg.norm(normal)))
        total = sum(row.get(f"n{i}", 0.0) for i in (1, 2, 3))
        if math.isfinite(total) and total > 0:
            weight = max(weight or 0.0, total)
        frames.append({"t": round(float(row["t"]), 6),
                       "platform": _round(list(rot.ravel()) + list(pos)),
                       "wheels": wheels, "contacts": contacts, "forces": forces,
                       "normals": normals,
                       # the values the page prints for the frame
                       "v": [_finite(row.get(c, math.nan)) for c in ("vx", "vy", "vz")],
                       "w": [_finite(row.get(c, math.nan)) for c in ("wx", "wy", "wz")],
                       "n": [_finite(row.get(f"n{i}", math.nan)) for i in (1, 2, 3)],
                       "lon": [_finite(row.get(f"t{i}_lon", math.nan)) for i in (1, 2, 3)],
                       "lat": [_finite(row.get(f"t{i}_lat", math.nan)) for i in (1, 2, 3)],
                       "camber": [_finite(math.degrees(row.get(f"delta{i}", math.nan)))
                                  for i in (2, 3)]})
    mounts = [_round(b) for b in robot.mount_points(geom)]
    terrain = _terrain_mesh(spec, traj)
    box = terrain["box"]
    force_scale = 0.25 / (weight / 3.0) if weight else 0.01
    return {"run_id": run["run_id"], "scene": run["scene"], "method": run["method"],
            "mode": scene_mode(run, ctx.references), "mu": run["mu"], "dt": run["dt"],
            "geometry": geom, "mounts": mounts, "terrain": terrain,
            "terrain_described": spec is not None,
            "force_scale": force_scale,
            # scale bar [m] and reference force [N] (arrow of force_bar * force_scale m)
            "scale_bar": nice_length(0.25 * max(box[1] - box[0], box[3] - box[2])),
            "force_bar": nice_length(weight / 3.0) if weight else 10.0,
            "frames": frames}


def write_replay(ctx, runs):
    """Write OUT/replay/ for the given runs; return (html snippet, notes)."""
    three = find_three()
    if three is None:
        return "", ["3D replay omitted: three.js (Debian package libjs-three) is not "
                    "installed in /usr/share/javascript/three"]
    runs = [r for r in runs if r is not None]
    if not runs:
        return "", ["3D replay omitted: no successful run with a trajectory"]
    folder = os.path.join(ctx.out_dir, "replay")
    os.makedirs(folder, exist_ok=True)
    for src, dst in THREE_FILES:
        shutil.copyfile(os.path.join(three, src), os.path.join(folder, dst))
    data = [replay_data(ctx, r) for r in runs]
    with open(os.path.join(folder, "data.js"), "w", encoding="utf-8") as handle:
        handle.write("window.QUASIROLL_REPLAY = ")
        json.dump(data, handle, separators=(",", ":"), allow_nan=False)
        handle.write(";\n")
    with open(os.path.join(folder, "index.html"), "w", encoding="utf-8") as handle:
        handle.write(viewer_page(VIEWER_HTML, "QUASIROLL_REPLAY")
                     .replace("@CHASSIS@", CHASSIS_HEX))
    names = ", ".join(f"{d['scene']} ({d['method']}, Δt={d['dt']:g} s, μ={d['mu']:g})"
                      for d in data)
    snippet = (
        '<p>Interactive replay of ' + names + ': terrain mesh, chassis (magenta), the '
        'three torus wheels at their steer and camber angles, contact forces as '
        'arrows (normal + traction, length ∝ force, with a reference arrow and the '
        'scale in the corner), the friction cone |t| ≤ μN at each contact to the same '
        'scale, x/y/z axes with a scale bar, the frame\'s values (t, speeds, wheel '
        'forces, camber) in the top-left box, time slider and play; drag to '
        'orbit, wheel to zoom; <code>?run=&lt;run_id&gt;</code> selects a run. Works offline (three.js r111 from Debian\'s libjs-three '
        'copied into <code>replay/</code>). <a href="replay/index.html">Open full '
        'page</a>.</p><iframe src="replay/index.html" title="3D replay" '
        'style="width:100%;height:560px;border:1px solid #ccc"></iframe>')
    return snippet, []


# The start of both 3D pages' script: `fail` (data-ready="error" and the
# message in #status), the check that three.js and the page's data (@DATA@)
# loaded, and `renderer`, a WebGL renderer (or fail when WebGL is missing).
VIEWER_BOOT_JS = r"""  "use strict";
  var body = document.body, status = document.getElementById("status");
  function fail(message) {
    body.setAttribute("data-ready", "error");
    status.textContent = "error: " + message;
  }
  if (typeof THREE === "undefined" || !window.@DATA@) {
    fail("three.js or data.js did not load");
    return;
  }
  var renderer;
  try {
    renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
  } catch (e) {
    fail("WebGL unavailable (" + e.message + ")");
    return;
  }"""


# The end of both pages' head and the start of their body: three.js, its
# orbit controls and the page's data.js (copied beside index.html), and the
# WebGL view.
VIEWER_PAGE_START = """<script src="three.min.js"></script>
<script src="OrbitControls.js"></script>
<script src="data.js"></script>
</head><body data-ready="0">
<div id="view"></div>"""


def viewer_page(template, data_name):
    """A 3D page's HTML: `template` with @PAGE_START@ and @BOOT@ replaced by
    the shared parts, its script reading window.<data_name>."""
    return (template.replace("@PAGE_START@", VIEWER_PAGE_START)
            .replace("@BOOT@", VIEWER_BOOT_JS.replace("@DATA@", data_name)))


VIEWER_HTML = r"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>quasiroll 3D replay</title>
<style>
html, body { margin: 0; height: 100%; overflow: hidden; font-family: sans-serif; }
#view { position: absolute; top: 0; left: 0; right: 0; bottom: 64px; }
#bar { position: absolute; left: 0; right: 0; bottom: 0; height: 64px;
       background: #f4f4f4; border-top: 1px solid #ccc; padding: 4px 10px;
       box-sizing: border-box; font-size: 13px; }
#bar input[type=range] { width: 55%; vertical-align: middle; }
#status { color: #555; }
#info { position: absolute; top: 6px; left: 6px; background: rgba(255,255,255,0.85);
        font: 12px monospace; padding: 4px 6px; border: 1px solid #ccc;
        white-space: pre; pointer-events: none; }
#key { position: absolute; top: 6px; right: 6px; background: rgba(255,255,255,0.85);
       font-size: 12px; padding: 4px 6px; border: 1px solid #ccc; pointer-events: none; }
</style>
@PAGE_START@
<div id="info"></div>
<div id="key"></div>
<div id="bar">
  <select id="run"></select>
  <button id="play">play</button>
  <input id="slider" type="range" min="0" max="0" value="0">
  <span id="time">t = 0 s</span><br>
  <span id="status">loading</span>
</div>
<script>
(function () {
@BOOT@
  var params = new URLSearchParams(window.location.search);
  var showRobot = params.get("norobot") !== "1";
  var view = document.getElementById("view");
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  view.appendChild(renderer.domElement);
  var scene = new THREE.Scene();
  scene.background = new THREE.Color(0xffffff);
  var camera = new THREE.PerspectiveCamera(40, 1, 0.01, 100);
  camera.up.set(0, 0, 1);
  var controls = new THREE.OrbitControls(camera, renderer.domElement);
  scene.add(new THREE.AmbientLight(0xffffff, 0.55));
  var sun = new THREE.DirectionalLight(0xffffff, 0.6);
  sun.position.set(-1, -2, 4);
  scene.add(sun);

  var runs = window.QUASIROLL_REPLAY, current = null, frame = 0, timer = null;
  var select = document.getElementById("run"), slider = document.getElementById("slider");
  // ?run=<run_id> (or a 0-based index): -1 when it names no run here.
  function pickRun(list, value) {
    if (value === null || value === "") return 0;
    for (var i = 0; i < list.length; i++) if (list[i].run_id === value) return i;
    if (/^[0-9]+$/.test(value)) return Math.min(+value, list.length - 1);
    return -1;
  }
  window.quasirollPickRun = pickRun;
  runs.forEach(function (r, i) {
    var o = document.createElement("option");
    o.value = i;
    o.textContent = r.scene + (r.mode ? " (" + r.mode + " mode)" : "") + " — " + r.method;
    select.appendChild(o);
  });

  function matrixOf(m) {  // row-major 3x3 rotation then translation
    var out = new THREE.Matrix4();
    out.set(m[0], m[1], m[2], m[9], m[3], m[4], m[5], m[10], m[6], m[7], m[8], m[11],
            0, 0, 0, 1);
    return out;
  }

  function terrainMesh(t) {
    var n = t.n, box = t.box, pos = [], col = [], idx = [];
    var lo = Math.min.apply(null, t.heights), hi = Math.max.apply(null, t.heights);
    for (var j = 0; j < n; j++) {
      for (var i = 0; i < n; i++) {
        var h = t.heights[j * n + i];
        pos.push(box[0] + (box[1] - box[0]) * i / (n - 1),
                 box[2] + (box[3] - box[2]) * j / (n - 1), h);
        var s = hi > lo ? (h - lo) / (hi - lo) : 0.5;
        col.push(0.55 + 0.35 * s, 0.7 + 0.2 * s, 0.45 + 0.2 * s);
      }
    }
    for (j = 0; j + 1 < n; j++) {
      for (i = 0; i + 1 < n; i++) {
        var a = j * n + i;
        idx.push(a, a + 1, a + n, a + 1, a + n + 1, a + n);
      }
    }
    var g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(pos, 3));
    g.setAttribute("color", new THREE.Float32BufferAttribute(col, 3));
    g.setIndex(idx);
    g.computeVertexNormals();
    return new THREE.Mesh(g, new THREE.MeshLambertMaterial(
      {vertexColors: THREE.VertexColors, side: THREE.DoubleSide}));
  }

  function label(text, size, colour) {  // a text sprite, size = height [m]
    var canvas = document.createElement("canvas"), ctx = canvas.getContext("2d");
    ctx.font = "bold 40px sans-serif";
    canvas.width = Math.ceil(ctx.measureText(text).width) + 12;
    canvas.height = 52;
    ctx.font = "bold 40px sans-serif";
    ctx.fillStyle = "rgba(255,255,255,0.75)";
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    ctx.fillStyle = colour || "#000000";
    ctx.textBaseline = "middle";
    ctx.fillText(text, 6, 27);
    var sprite = new THREE.Sprite(new THREE.SpriteMaterial(
      {map: new THREE.CanvasTexture(canvas), depthTest: false}));
    sprite.scale.set(size * canvas.width / canvas.height, size, 1);
    sprite.renderOrder = 20;
    return sprite;
  }

  function segment(a, b, colour) {
    var g = new THREE.BufferGeometry();
    g.setAttribute("position", new THREE.Float32BufferAttribute(a.concat(b), 3));
    return new THREE.Line(g, new THREE.LineBasicMaterial({color: colour}));
  }

  // Axes (x red, y green, z blue) and a scale bar at the terrain's corner, a
  // reference force arrow beside them: the scale of lengths and of forces.
  function guides(r) {
    var out = new THREE.Group(), b = r.terrain.box, L = r.scale_bar;
    var z0 = Math.max.apply(null, r.terrain.heights) + 0.01;
    var o = [b[0] + 0.15 * L, b[3] - 1.3 * L, z0];  // back left: in view
    var axes = new THREE.AxesHelper(L);
    axes.position.set(o[0], o[1], o[2]);
    out.add(axes);
    var h = 0.09 * L;
    [["x", [L, 0, 0], "#d62728"], ["y", [0, L, 0], "#2ca02c"],
     ["z", [0, 0, L], "#1f77b4"]].forEach(function (a) {
      var s = label(a[0], h, a[2]);
      s.position.set(o[0] + 1.12 * a[1][0], o[1] + 1.12 * a[1][1], o[2] + 1.12 * a[1][2]);
      out.add(s);
    });
    var y = o[1] - 0.25 * L;
    out.add(segment([o[0], y, z0], [o[0] + L, y, z0], 0x000000));
    out.add(segment([o[0], y - 0.05 * L, z0], [o[0], y + 0.05 * L, z0], 0x000000));
    out.add(segment([o[0] + L, y - 0.05 * L, z0], [o[0] + L, y + 0.05 * L, z0], 0x000000));
    var sb = label(L + " m", h);
    sb.position.set(o[0] + 0.5 * L, y - 0.18 * L, z0);
    out.add(sb);
    var fl = r.force_bar * r.force_scale, fx = o[0] + 1.6 * L;
    var ref = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(fx, o[1], z0),
                                    fl, 0x444444, Math.min(0.03, 0.3 * fl),
                                    Math.min(0.015, 0.15 * fl));
    out.add(ref);
    var fb = label(r.force_bar + " N", h, "#444444");
    fb.position.set(fx, o[1], z0 + fl + 0.1 * L);
    out.add(fb);
    return out;
  }

  // Friction cone |t| <= mu N at a contact: apex at the contact, axis along
  // the terrain normal, height N * force_scale (the force arrows' scale),
  // radius mu times that; a force arrow inside it is feasible.
  function coneMesh(mu) {
    var g = new THREE.ConeGeometry(mu, 1, 32, 1, true);
    g.rotateX(Math.PI);
    g.translate(0, 0.5, 0);
    var m = new THREE.Mesh(g, new THREE.MeshBasicMaterial(
      {color: 0xff8c00, transparent: true, opacity: 0.22, side: THREE.DoubleSide,
       depthWrite: false}));
    m.renderOrder = 5;
    return m;
  }

  function fmt(v, d) { return v === null || v === undefined ? "n/a" : v.toFixed(d); }

  var group = null, parts = null;
  function build(r) {
    if (group) scene.remove(group);
    group = new THREE.Group();
    group.add(terrainMesh(r.terrain));
    var robotGroup = new THREE.Group();
    robotGroup.visible = showRobot;
    var g = r.geometry;
    var chassisGeom = new THREE.BufferGeometry();
    chassisGeom.setAttribute("position", new THREE.Float32BufferAttribute(
      [].concat(r.mounts[0], r.mounts[1], r.mounts[2]), 3));
    var chassis = new THREE.Mesh(chassisGeom, new THREE.MeshBasicMaterial(
      {color: "@CHASSIS@", side: THREE.DoubleSide}));
    chassis.matrixAutoUpdate = false;
    robotGroup.add(chassis);
    var wheelMat = new THREE.MeshLambertMaterial({color: 0x303030});
    var wheels = [], arrows = [], cones = [];
    var colours = [0x1b9e77, 0xd95f02, 0x7570b3];
    for (var k = 0; k < 3; k++) {
      var w = new THREE.Mesh(new THREE.TorusGeometry(g.R, g.r, 12, 36), wheelMat);
      w.matrixAutoUpdate = false;
      robotGroup.add(w);
      wheels.push(w);
      var arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(),
                                        0.1, colours[k], 0.03, 0.015);
      // drawn over the wheel (the normal force points through the torus)
      arrow.line.material.depthTest = false;
      arrow.cone.material.depthTest = false;
      arrow.renderOrder = 10;
      robotGroup.add(arrow);
      arrows.push(arrow);
      var cone = coneMesh(r.mu);
      robotGroup.add(cone);
      cones.push(cone);
    }
    group.add(robotGroup);
    group.add(guides(r));
    scene.add(group);
    parts = {chassis: chassis, wheels: wheels, arrows: arrows, cones: cones};
    document.getElementById("key").innerHTML =
      "axes x/y/z, bar = " + r.scale_bar + " m<br>force arrows: " +
      (1 / r.force_scale).toPrecision(3) + " N per m (grey arrow = " + r.force_bar +
      " N)<br>orange cone: friction cone |t| &le; &mu;N, &mu; = " + r.mu;
    var b = r.terrain.box, f0 = r.frames[0];
    var cx = (b[0] + b[1]) / 2, cy = (b[2] + b[3]) / 2, cz = f0.platform[11];
    var span = Math.max(b[1] - b[0], b[3] - b[2]);
    controls.target.set(cx, cy, cz);
    camera.position.set(cx - 0.3 * span, cy - 0.7 * span, cz + 0.45 * span);
    controls.update();
    slider.max = r.frames.length - 1;
  }

  function show(k) {
    var r = current, f = r.frames[k];
    frame = k;
    slider.value = k;
    parts.chassis.matrix.copy(matrixOf(f.platform));
    for (var i = 0; i < 3; i++) {
      parts.wheels[i].matrix.copy(matrixOf(f.wheels[i]));
      var F = new THREE.Vector3(f.forces[i][0], f.forces[i][1], f.forces[i][2]);
      var len = F.length() * r.force_scale;
      var a = parts.arrows[i];
      a.visible = len > 1e-6;
      a.position.set(f.contacts[i][0], f.contacts[i][1], f.contacts[i][2]);
      if (a.visible) {
        a.setDirection(F.normalize());
        a.setLength(len, Math.min(0.03, 0.3 * len), Math.min(0.015, 0.15 * len));
      }
      var c = parts.cones[i], N = f.n[i], h = (N || 0) * r.force_scale;
      c.visible = h > 1e-6;
      if (c.visible) {
        c.position.set(f.contacts[i][0], f.contacts[i][1], f.contacts[i][2]);
        c.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0),
          new THREE.Vector3(f.normals[i][0], f.normals[i][1], f.normals[i][2]));
        c.scale.set(h, h, h);
      }
    }
    var speed = f.v[0] === null ? null : Math.sqrt(f.v[0] * f.v[0] + f.v[1] * f.v[1] +
                                                   f.v[2] * f.v[2]);
    var lines = ["run " + r.run_id, "t = " + fmt(f.t, 3) + " s",
                 "|v| = " + fmt(speed, 4) + " m/s  v = (" + f.v.map(function (x) {
                   return fmt(x, 4); }).join(", ") + ")",
                 "w = (" + f.w.map(function (x) { return fmt(x, 4); }).join(", ") + ") rad/s",
                 "wheel  N [N]   t_lon [N]  t_lat [N]  |t|/(mu N)"];
    for (i = 0; i < 3; i++) {
      var tt = f.lon[i] === null ? null : Math.sqrt(f.lon[i] * f.lon[i] + f.lat[i] * f.lat[i]);
      lines.push("  " + (i + 1) + "   " + fmt(f.n[i], 3) + "   " + fmt(f.lon[i], 3) + "   " +
                 fmt(f.lat[i], 3) + "   " + (f.n[i] > 0 && tt !== null ?
                 fmt(tt / (r.mu * f.n[i]), 3) : "n/a"));
    }
    lines.push("camber  d2 = " + fmt(f.camber[0], 2) + " deg  d3 = " +
               fmt(f.camber[1], 2) + " deg");
    document.getElementById("info").textContent = lines.join("\n");
    document.getElementById("time").textContent =
      "t = " + f.t.toFixed(2) + " s (frame " + (k + 1) + "/" + r.frames.length + ")";
  }

  function resize() {
    var w = view.clientWidth || 800, h = view.clientHeight || 480;
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }

  function render() { renderer.render(scene, camera); }

  function selectRun(i) {
    current = runs[i];
    build(current);
    show(0);
    status.textContent = current.scene + ": " + current.frames.length + " frames, " +
      current.method + ", dt " + current.dt + " s, mu " + current.mu +
      (current.terrain_described ? "" : " (no terrain file: flat plane drawn)");
  }

  select.addEventListener("change", function () { selectRun(+select.value); render(); });
  slider.addEventListener("input", function () { show(+slider.value); render(); });
  document.getElementById("play").addEventListener("click", function () {
    if (timer) { clearInterval(timer); timer = null; this.textContent = "play"; return; }
    this.textContent = "pause";
    timer = setInterval(function () {
      show((frame + 1) % current.frames.length);
      render();
    }, 40);
  });
  controls.addEventListener("change", render);
  window.addEventListener("resize", function () { resize(); render(); });

  resize();
  var wanted = pickRun(runs, params.get("run"));
  selectRun(Math.max(wanted, 0));
  select.value = Math.max(wanted, 0);
  if (wanted < 0) status.textContent = "run " + params.get("run") +
    " is not in this replay; showing " + status.textContent;
  var start = +(params.get("frame") || 0);
  show(Math.max(0, Math.min(start, current.frames.length - 1)));
  render();
  var gl = renderer.getContext();
  if (!gl || gl.isContextLost()) { fail("no WebGL context"); return; }
  body.setAttribute("data-ready", "1");
  status.textContent = "ready — " + status.textContent;
})();
</script>
</body></html>
"""
