"""Reading and validating a quasiroll results directory.

Every problem with the input raises ReportError with a one-line message; the
entry point turns it into `make_report: <message>` on stderr and exit code 2.
"""

import csv
import json
import math
import os

import numpy as np


class ReportError(Exception):
    """Bad input: the message is printed as one line, exit code 2."""


# The runs.csv schema: bench/io/runs_columns.tsv, the one definition the
# C++ writer embeds. Beside the package in the source tree (reports/..) and
# in an install (<prefix>/share/quasiroll/{reports,bench/io}).
RUNS_SCHEMA_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "bench", "io", "runs_columns.tsv")
SCHEMA_TYPES = ("string", "int", "double", "json")


def read_runs_schema(path=RUNS_SCHEMA_PATH):
    """The runs.csv columns in order: dicts with name, type, unit, doc."""
    try:
        with open(path, encoding="utf-8") as handle:
            lines = handle.read().splitlines()
    except OSError as exc:
        raise ReportError(f"cannot read the runs.csv schema: {exc}") from None
    if not lines or lines[0].split("\t") != ["name", "type", "unit", "doc"]:
        raise ReportError(f"{path}: expected the header name, type, unit, doc")
    columns = []
    for line_no, line in enumerate(lines[1:], start=2):
        fields = line.split("\t")
        if len(fields) != 4 or fields[1] not in SCHEMA_TYPES:
            raise ReportError(f"{path} line {line_no}: expected name, type "
                              f"({'|'.join(SCHEMA_TYPES)}), unit, doc")
        columns.append(dict(zip(("name", "type", "unit", "doc"), fields)))
    return columns


RUNS_SCHEMA = read_runs_schema()
RUNS_COLUMNS = [c["name"] for c in RUNS_SCHEMA]

# What the report needs of a runs.csv (older files lack later columns).
REQUIRED_COLUMNS = [
    "scene", "nlp", "dae", "coupling", "dt", "tol", "sigma", "eps", "mu",
    "seed", "status", "stop_reason", "t_reached", "wall_s", "repeats",
    "nlp_solves", "nlp_iters", "rhs_evals", "steps", "rejected_steps",
    "err_pos_rms", "err_pos_max", "err_final", "err_rot_max", "err_force_rms",
    "err_slip", "drift_max", "drift_final", "gap_max",
]

# Types from the schema: string and json columns stay strings, int and
# double columns are parsed as floats. seed is an int that the report only
# uses as a label and a grouping key (problems.py): kept as text.
STRING_COLUMNS = {c["name"] for c in RUNS_SCHEMA
                  if c["type"] in ("string", "json")} | {"seed"}
NUMERIC_COLUMNS = set(RUNS_COLUMNS) - STRING_COLUMNS

# Columns that a row lacking them gets, as nan or "" by their type: added
# later (issue #14, docs/harness.md), the report omits what needs a missing
# one and says so on the page. Others stay absent (e.g. ref_status, whose
# absence selection.py reads as a reference that succeeded).
DEFAULTED_COLUMNS = [
    "mu_min", "roughness", "t_end", "kkt_residual", "t_reached_frac",
    "wall_s_median", "wall_s_min", "wall_s_max", "wall_per_sim_s",
    "qs_inertia_ratio", "ref_mu_min", "ref_err_est", "cause", "cause_detail",
    "wall_s_all", "host", "cpu_model", "ref_hash", "terrain", "rk_method",
    "sliding_distance", "creep_distance", "wall_s_q1", "wall_s_q3", "wall_s_iqr",
    "timing_exclusive", "drift_step_max"]

for _name in REQUIRED_COLUMNS + DEFAULTED_COLUMNS:
    assert _name in RUNS_COLUMNS, f"{_name} is no runs.csv column ({RUNS_SCHEMA_PATH})"

WHEEL_COLUMNS = ("c{i}_x", "c{i}_y", "c{i}_z", "n{i}", "t{i}_lon", "t{i}_lat",
                 "slip{i}", "use{i}")
TRAJECTORY_COLUMNS = (
    ["t", "x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz",
     "wx", "wy", "wz", "phi1", "alpha1", "delta2", "alpha2", "delta3", "alpha3"]
    + [name.format(i=i) for i in (1, 2, 3) for name in WHEEL_COLUMNS]
    + ["drift", "gap_max", "nlp_status", "nlp_iters"]
)

SUCCESS = "success"


def parse_number(text):
    """Float of a CSV field; empty, 'nan' and missing fields become nan."""
    if text is None:
        return math.nan
    text = text.strip()
    if text == "" or text.lower() in ("nan", "-nan", "na", "null", "none"):
        return math.nan
    return float(text)


def is_finite(value):
    return value is not None and isinstance(value, float) and math.isfinite(value)


# ------------------------------------------------------------------ methods
#
# A method is what ran (docs/harness.md, "Method identity"): runs.csv
# `method` = "<nlp>[opts]/<dae>[opts]/<coupling>", [opts] the backend options
# that differ from the backend's defaults, "name=value" sorted by name, e.g.
# "newton/rk-projection[rk_method=dp54]/coupled". Option variants of a pair
# are different methods: never pooled.

# Older runs.csv without `method`: the shorthand columns name these
# integrator options, at the built-in integrators' defaults (docs/harness.md).
# A value other than the default joins the method, if the row's
# `dae_options` (when written) shows that the integrator has the option.
# Other backend options of such files are not recovered.
LEGACY_OPTION_COLUMNS = [("rk_method", "rk_method", "rk4"),
                         ("sigma", "baumgarte_sigma", 5.0),
                         ("dae_index", "dae_index", 2.0)]


def number_text(value):
    """A number as the harness writes it (Num: shortest round trip, 15 not 15.0)."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") else text


def _split_outside_brackets(text, sep):
    parts, depth, start = [], 0, 0
    for i, char in enumerate(text):
        depth += {"[": 1, "]": -1}.get(char, 0)
        if char == sep and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    return parts + [text[start:]]


def _backend_part(part):
    name, bracket, rest = part.partition("[")
    options = []
    if bracket:
        for item in _split_outside_brackets(rest[:-1] if rest.endswith("]") else rest, ","):
            key, _, value = item.partition("=")
            if key:
                options.append((key, value))
    return name, options


def parse_method(method):
    """(nlp, nlp_options, dae, dae_options, coupling) of a method id; options
    as [(name, value)] in the id's order."""
    parts = _split_outside_brackets(method, "/") + ["", "", ""]
    nlp, nlp_options = _backend_part(parts[0])
    dae, dae_options = _backend_part(parts[1])
    return nlp, nlp_options, dae, dae_options, parts[2]


def format_method(nlp, nlp_options, dae, dae_options, coupling):
    def part(name, options):
        listed = ",".join(f"{k}={v}" for k, v in sorted(options))
        return name + (f"[{listed}]" if listed else "")
    return f"{part(nlp, nlp_options)}/{part(dae, dae_options)}/{coupling}"


def method_base(method):
    """The backend pair and coupling of a method, without its options."""
    nlp, _, dae, _, coupling = parse_method(method)
    return f"{nlp}/{dae}/{coupling}"


def is_variant(method):
    """True for a method with a backend option off its default."""
    return method != method_base(method)


def method_options(method):
    """{name: value} of every non-default option of the method (both backends)."""
    _, nlp_options, _, dae_options, _ = parse_method(method)
    return dict(nlp_options + dae_options)


def method_without(method, names):
    """The method without the options `names` (e.g. a chart axis sweeping one)."""
    nlp, nlp_options, dae, dae_options, coupling = parse_method(method)
    keep = [(k, v) for k, v in nlp_options if k not in names]
    return format_method(nlp, keep, dae,
                         [(k, v) for k, v in dae_options if k not in names], coupling)


def _legacy_dae_options(run):
    names = None
    try:
        used = json.loads(run.get("dae_options") or "null")
        names = set(used) if isinstance(used, dict) else None
    except ValueError:
        pass
    options = []
    for column, option, default in LEGACY_OPTION_COLUMNS:
        value = run.get(column)
        if value is None or value == "" or (names is not None and option not in names):
            continue
        if isinstance(value, float):
            if not math.isfinite(value) or value == default:
                continue
            value = number_text(value)
        elif value == default:
            continue
        options.append((option, value))
    return options


def dae_option_table(run):
    """{name: value} of the integrator's option table as the run used it
    (runs.csv `dae_options`), or None when the row does not carry it."""
    try:
        table = json.loads(run.get("dae_options") or "null")
    except (TypeError, ValueError):
        return None
    return table if isinstance(table, dict) else None


def dae_option_known(run, name):
    """True / False when the row shows whether its integrator has the option
    `name` (`dae_options` written, or the method id naming it); None when it
    cannot tell (older rows)."""
    table = dae_option_table(run)
    if table is not None:
        return name in table
    if name in dict(parse_method(run.get("method", ""))[3]):
        return True
    return None


def has_dae_option(run, name):
    """True when the run's integrator has the option `name` (e.g.
    baumgarte_sigma): from `dae_options` where written, else from the
    method id; for older rows without either, from a shorthand column that
    holds a number."""
    known = dae_option_known(run, name)
    if known is not None:
        return known
    column = {option: col for col, option, _ in LEGACY_OPTION_COLUMNS}.get(name)
    return column is not None and is_finite(run.get(column, math.nan))


def dae_option(run, name, default=None):
    """The value of an integrator option: `dae_options`, else the method id,
    else the shorthand column; `default` when the integrator lacks it."""
    table = dae_option_table(run)
    if table is not None:
        return table.get(name, default)
    options = dict(parse_method(run.get("method", ""))[3])
    if name in options:
        return options[name]
    column = {option: col for col, option, _ in LEGACY_OPTION_COLUMNS}.get(name)
    value = run.get(column) if column else None
    return default if value in (None, "") or (isinstance(value, float)
                                              and not math.isfinite(value)) else value


def method_name(run):
    """runs.csv `method`; for older files derived from nlp/dae/coupling and
    the shorthand columns (LEGACY_OPTION_COLUMNS)."""
    if run.get("method"):
        return run["method"]
    return format_method(run["nlp"], [], run["dae"], _legacy_dae_options(run),
                         run["coupling"])


def is_success(run):
    return run["status"] == SUCCESS


def _read_csv_rows(path, label):
    if not os.path.isfile(path):
        raise ReportError(f"{label} not found: {path}")
    try:
        with open(path, newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ReportError(f"cannot read {label}: {exc}") from None
    rows = [row for row in rows if any(field.strip() for field in row)]
    if not rows:
        raise ReportError(f"{label} is empty")
    header = [name.strip() for name in rows[0]]
    return header, rows[1:]


def _check_columns(header, required, label):
    for column in required:
        if column not in header:
            raise ReportError(f"{label} is missing column '{column}'")


def _typed_run(record, line_no):
    """Known numeric columns must parse; extra columns (runs.csv only grows
    additively) stay strings unless they look like numbers."""
    run = {}
    for key, text in record.items():
        if key in STRING_COLUMNS:
            run[key] = (text or "").strip()
            continue
        try:
            run[key] = parse_number(text)
        except ValueError:
            if key not in NUMERIC_COLUMNS:
                run[key] = (text or "").strip()
                continue
            raise ReportError(
                f"runs.csv line {line_no}: column '{key}' is not a number: "
                f"'{text.strip()}'") from None
    return run


def read_runs(results_dir):
    """All rows of DIR/runs.csv as dicts with typed values.

    Sets `method` (the column, or derived for older files: method_name), a
    `run_id` when the column is missing, and nan for absent optional numeric
    columns.
    """
    path = os.path.join(results_dir, "runs.csv")
    header, body = _read_csv_rows(path, "runs.csv")
    _check_columns(header, REQUIRED_COLUMNS, "runs.csv")
    if not body:
        raise ReportError("runs.csv has a header but no runs")
    runs = []
    for index, fields in enumerate(body):
        record = {name: (fields[i] if i < len(fields) else "")
                  for i, name in enumerate(header) if name}
        run = _typed_run(record, index + 2)
        if not run["status"]:
            raise ReportError(f"runs.csv line {index + 2}: empty status")
        run.setdefault("run_id", f"row{index + 1}")
        if not run["run_id"]:
            run["run_id"] = f"row{index + 1}"
        for column in DEFAULTED_COLUMNS:
            run.setdefault(column, "" if column in STRING_COLUMNS else math.nan)
        run["timings"] = parse_timings(run.get("wall_s_all", ""))
        run["method"] = method_name(run)
        run["row"] = index + 1
        runs.append(run)
    return runs, header


def parse_timings(text):
    """wall_s_all ("0.1;0.12;...") as a list of floats; [] when absent."""
    values = []
    for part in (text or "").split(";"):
        try:
            value = parse_number(part)
        except ValueError:
            continue
        if math.isfinite(value):
            values.append(value)
    return values


def has_column(header, name):
    return name in header


def trajectory_path(results_dir, run):
    return os.path.join(results_dir, "trajectories", f"{run['run_id']}.csv")


def read_trajectory(path):
    """A trajectory CSV as {column: numpy array}; `nlp_status` stays strings."""
    label = "trajectories/" + os.path.basename(path)
    header, body = _read_csv_rows(path, label)
    _check_columns(header, TRAJECTORY_COLUMNS, label)
    columns = {name: [] for name in header}
    for line_no, fields in enumerate(body, start=2):
        for i, name in enumerate(header):
            columns[name].append(fields[i] if i < len(fields) else "")
    table = {}
    for name, values in columns.items():
        if name == "nlp_status":
            table[name] = [v.strip() for v in values]
            continue
        try:
            table[name] = np.array([parse_number(v) for v in values], float)
        except ValueError:
            raise ReportError(f"{label}: column '{name}' has a non-number") from None
    return table


def read_switches(path):
    """switches/<run_id>.csv (docs/formats.md) as a list of dicts with t,
    wheel, from, to, located, kind ("switch", "creep_reversal" or
    "solution_jump"; files from before the column: "switch") and the
    bracket t_lower, t_upper (nan without the columns); None if the
    file does not exist (a run from before the file was written, or from a
    merge that did not copy it)."""
    if not os.path.isfile(path):
        return None
    label = "switches/" + os.path.basename(path)
    header, body = _read_csv_rows(path, label)
    _check_columns(header, ("t", "wheel", "from", "to", "located"), label)
    rows = []
    for fields in body:
        row = dict(zip(header, fields))
        try:
            rows.append({"t": parse_number(row["t"]), "wheel": int(row["wheel"]),
                         "from": row["from"], "to": row["to"],
                         "located": row["located"] == "true",
                         "kind": row.get("kind") or "switch",
                         "t_lower": parse_number(row.get("t_lower") or "nan"),
                         "t_upper": parse_number(row.get("t_upper") or "nan")})
        except ValueError:
            raise ReportError(f"{label}: a row has a non-number") from None
    return rows


class TrajectoryStore:
    """Loads trajectories on demand and remembers them."""

    def __init__(self, results_dir):
        self.results_dir = results_dir
        self._cache = {}

    def has(self, run):
        return os.path.isfile(trajectory_path(self.results_dir, run))

    def get(self, run):
        key = run["run_id"]
        if key not in self._cache:
            table = read_trajectory(trajectory_path(self.results_dir, run))
            self._cache[key] = table if len(table["t"]) else None
        return self._cache[key]

    def switches(self, run):
        """The run's located stick/slide switches (read_switches)."""
        return read_switches(os.path.join(self.results_dir, "switches",
                                          f"{run['run_id']}.csv"))


def read_meta(results_dir):
    """DIR/meta.json as a dict ({} if missing or not a JSON object)."""
    path = os.path.join(results_dir, "meta.json")
    if not os.path.isfile(path):
        return {}
    try:
        with open(path, encoding="utf-8") as handle:
            meta = json.load(handle)
    except (OSError, ValueError):
        return {"_warning": "meta.json is not valid JSON"}
    return meta if isinstance(meta, dict) else {}


def read_references(results_dir):
    """{hash: dict} of DIR/references/<hash>.json (unreadable files skipped)."""
    folder = os.path.join(results_dir, "references")
    refs = {}
    if not os.path.isdir(folder):
        return refs
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".json"):
            continue
        try:
            with open(os.path.join(folder, name), encoding="utf-8") as handle:
                spec = json.load(handle)
        except (OSError, ValueError):
            continue
        if isinstance(spec, dict):
            refs[spec.get("hash", name[:-5])] = spec
    return refs


def read_terrain(results_dir, scene):
    """DIR/terrains/<scene>.json as a dict, or None when absent/unusable."""
    path = os.path.join(results_dir, "terrains", f"{scene}.json")
    if not os.path.isfile(path):
        return None
    try:
        with open(path, encoding="utf-8") as handle:
            spec = json.load(handle)
    except (OSError, ValueError):
        return None
    if not isinstance(spec, dict) or spec.get("type") not in (
            "gaussians", "plane", "incline"):
        return None
    return spec
