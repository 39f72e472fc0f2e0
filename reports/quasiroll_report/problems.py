"""What may be compared with what, and the fixed styles of the report.

A *problem* is everything that fixes the exact solution a run approximates:
scene (with its mode and robot), μ, terrain (seed, roughness) and t_end. Runs
of one problem share a reference (`ref_hash`, docs/harness.md); only they may
share a chart, a Pareto front or a table row. Results without `ref_hash`
fall back to the tuple of those columns.

Styles: colour = NLP backend, marker = integrator, line style = coupling,
so a method looks the same in every figure. An option variant of a backend
pair (a method with non-default backend options, data.parse_method) keeps
the pair's colour and marker, hollow, with a dash pattern of its own. Backends are styled by their
position in the build's backend list (meta.json "backends", written from the
registry in name order, see use_backends), so every report of one build
styles them alike; a name not in that list gets a stable pick from its hash.
No backend is named here.
"""

import math
import re
import zlib
from collections import namedtuple

from .data import is_finite, is_variant, parse_method

REFERENCE_COLOUR = "#000000"
_COLOURS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#8c564b", "#9467bd",
            "#e377c2", "#17becf", "#bcbd22", "#7f7f7f", "#393b79"]
_MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "h", "p", "<", ">"]
COUPLING_LINES = {"zoh": "-", "coupled": "--"}
# Dash patterns of option variants, unlike the coupling lines.
VARIANT_DASHES = [(0, (7, 2, 1, 2)), (0, (1, 1)), (0, (9, 2, 2, 2, 2, 2)),
                  (0, (4, 1, 1, 1, 1, 1)), (0, (12, 3)), (0, (2, 2, 6, 2))]
VARIANT_FACE = "white"
# Backend names in the build's order (use_backends); empty until a report
# reads its meta.json.
_BACKENDS = {"nlp": [], "dae": []}


def use_backends(meta):
    """Takes the backend lists of a results directory's meta.json."""
    backends = meta.get("backends") if isinstance(meta, dict) else None
    for kind in ("nlp", "dae"):
        entries = backends.get(kind, []) if isinstance(backends, dict) else []
        _BACKENDS[kind] = [e["name"] for e in entries
                           if isinstance(e, dict) and isinstance(e.get("name"), str)]


def _stable_pick(name, choices):
    return choices[zlib.crc32(name.encode("utf-8")) % len(choices)]


def _style(kind, name, choices):
    names = _BACKENDS[kind]
    if name in names and names.index(name) < len(choices):
        return choices[names.index(name)]
    return _stable_pick(name, choices)


def nlp_colour(nlp):
    return REFERENCE_COLOUR if nlp == "reference" else _style("nlp", nlp, _COLOURS)


def dae_marker(dae):
    return _style("dae", dae, _MARKERS)


# Integrator colours for panels whose lines share one NLP (the drift
# representatives, Fig. 15), where the NLP colour would paint them alike:
# by the integrator's place in meta.json's backend list, as the markers.
_DAE_COLOURS = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02",
                "#a6761d", "#666666"]


def dae_colour(dae):
    return _style("dae", dae, _DAE_COLOURS)


def coupling_line(coupling):
    return COUPLING_LINES.get(coupling, ":")


MethodStyle = namedtuple("MethodStyle", "colour marker linestyle facecolor")


def method_style(method, variant_rank=None):
    """The MethodStyle of a method id. A variant's dash pattern is
    VARIANT_DASHES[variant_rank] (selection.method_styles ranks the variants
    of each pair), else a stable pick from its options."""
    nlp, _, dae, _, coupling = parse_method(method)
    colour, marker = nlp_colour(nlp), dae_marker(dae)
    if not is_variant(method):
        return MethodStyle(colour, marker, coupling_line(coupling), colour)
    dash = (VARIANT_DASHES[variant_rank % len(VARIANT_DASHES)]
            if variant_rank is not None else _stable_pick(method, VARIANT_DASHES))
    return MethodStyle(colour, marker, dash, VARIANT_FACE)


def plot_style(style):
    """Keyword arguments of Axes.plot / errorbar for a MethodStyle."""
    return {"color": style.colour, "marker": style.marker,
            "linestyle": style.linestyle, "markerfacecolor": style.facecolor}


# ------------------------------------------------------------------ problems

def _num_key(value):
    return round(value, 12) if is_finite(value) else None


def problem_key(run):
    """Hashable identity of the run's problem."""
    if run.get("ref_hash"):
        return ("ref", run["ref_hash"])
    return ("cols", run["scene"], run.get("terrain", ""), _num_key(run["mu"]),
            run.get("seed", ""), _num_key(run.get("roughness", math.nan)),
            _num_key(run.get("t_end", math.nan)))


def reference_field(reference, name):
    """A `name=value` field of a reference's canonical key text, or ''."""
    key = (reference or {}).get("key", "")
    match = re.search(r"(?:^|[;{|])" + re.escape(name) + r"=([^;}|]*)", key)
    return match.group(1) if match else ""


def scene_mode(run, references):
    """'paper' or 'pvc' from the run's reference key; '' when unknown."""
    mode = reference_field(references.get(run.get("ref_hash", "")), "mode")
    if mode:
        return mode
    return "pvc" if "pvc" in run["scene"].lower() else ""


def _short(value):
    return f"{value:g}" if is_finite(value) else ""


def problem_label(run, references=None, omit=()):
    """Short human label: 'paper · pvc · μ=0.5 · 20 s' (+ seed, roughness).
    `omit` names fields left out ("mu", "seed", "roughness"): the axis of a
    chart whose columns vary it."""
    parts = [run["scene"]]
    mode = scene_mode(run, references or {})
    if mode:
        parts.append(f"{mode} mode")
    if is_finite(run["mu"]) and "mu" not in omit:
        parts.append(f"μ={_short(run['mu'])}")
    if run.get("seed") and "seed" not in omit:
        parts.append(f"seed {run['seed']}")
    rough = run.get("roughness", math.nan)
    if is_finite(rough) and not math.isclose(rough, 1.0) and "roughness" not in omit:
        parts.append(f"roughness {_short(rough)}")
    t_end = run.get("t_end", math.nan)
    if is_finite(t_end):
        parts.append(f"{_short(t_end)} s")
    return " · ".join(parts)


def _distinct(rows, get):
    values = []
    for run in rows:
        value = get(run)
        if isinstance(value, float) and not math.isfinite(value):
            value = None
        if value in ("",):
            value = None
        if not any(value == v or (isinstance(value, float) and isinstance(v, float)
                                  and math.isclose(value, v, rel_tol=1e-9))
                   for v in values):
            values.append(value)
    return values


def fixed_label(rows, references=None, omit=()):
    """Title of a panel of a sweep: the parameters held fixed over `rows`
    (scene, mode, μ, seed, roughness, t_end, Δt, ε), each only when every row
    has the same value; `omit` names the swept ones ("mu", "seed",
    "roughness", "dt", "eps"), never taken from one row."""
    if not rows:
        return ""
    parts = []

    def single(name, get, text):
        if name in omit:
            return
        values = _distinct(rows, get)
        if len(values) == 1 and values[0] is not None:
            parts.append(text(values[0]))

    single("scene", lambda r: r["scene"], str)
    single("mode", lambda r: scene_mode(r, references or {}), lambda m: f"{m} mode")
    single("mu", lambda r: r["mu"], lambda v: f"μ={_short(v)}")
    single("seed", lambda r: r.get("seed", ""), lambda v: f"seed {v}")
    rough = _distinct(rows, lambda r: r.get("roughness", math.nan))
    if "roughness" not in omit and len(rough) == 1 and rough[0] is not None \
            and not math.isclose(rough[0], 1.0):
        parts.append(f"roughness {_short(rough[0])}")
    single("t_end", lambda r: r.get("t_end", math.nan), lambda v: f"{_short(v)} s")
    single("dt", lambda r: r["dt"], lambda v: f"Δt={_short(v)} s")
    single("eps", lambda r: r.get("eps", math.nan), lambda v: f"ε={_short(v)} m/s")
    return " · ".join(parts)


def problem_sort_key(run):
    t_end = run.get("t_end", math.nan)
    return (-(t_end if is_finite(t_end) else 0.0), run["scene"],
            run["mu"] if is_finite(run["mu"]) else 0.0, run.get("seed", ""))


def group_by_problem(rows):
    """[(key, rows)] in a stable order (longest t_end first, then scene, μ)."""
    groups = {}
    for run in rows:
        groups.setdefault(problem_key(run), []).append(run)
    return sorted(groups.items(), key=lambda kv: problem_sort_key(kv[1][0]))


def robot_geometry(reference):
    """Robot dimensions from a reference's key text (docs/harness.md), with the
    defaults of docs/model.md for fields it lacks."""
    geometry = {"a": 0.25, "b": 0.25, "track": 0.4, "z_h": 0.05, "R": 0.08,
                "r": 0.02, "e": 0.0}
    key = (reference or {}).get("key", "")
    match = re.search(r"robot\{([^}]*)\}", key)
    if match:
        for field in match.group(1).split(";"):
            name, _, value = field.partition("=")
            try:
                if name in geometry:
                    geometry[name] = float(value)
            except ValueError:
                pass
    return geometry
