"""Reproduction appendix: the command, machine, versions, and copies of the
suite and scene files next to the report."""

import os
import platform
import re
import shutil
import sys

import matplotlib
import numpy as np


def fnv1a64(data):
    """FNV-1a 64 of bytes, as 16 hex digits (the harness's suite hash)."""
    value = 0xcbf29ce484222325
    for byte in data:
        value ^= byte
        value = (value * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"{value:016x}"


def _suite_info(meta):
    suite = meta.get("suite")
    return suite if isinstance(suite, dict) else {}


def _scene_files(suite_text):
    """Relative scene paths named by `file:` keys of a suite's text."""
    return sorted(set(re.findall(r"\bfile:\s*['\"]?([^,'\"}\s]+)", suite_text)))


def copy_inputs(meta, results_dir, out_dir):
    """Copy the suite file and its scene files into OUT/repro/.

    Returns dict(files=[(label, relative path)], notes=[str])."""
    info = _suite_info(meta)
    notes, files = [], []
    candidates = [info.get("absolute_path"), info.get("path")]
    if info.get("path"):
        candidates.append(os.path.join(results_dir, info["path"]))
    path = next((p for p in candidates if p and os.path.isfile(p)), None)
    if path is None:
        notes.append("suite file not found (meta.json suite.path/absolute_path): "
                      "not copied")
        return {"files": files, "notes": notes}
    repro = os.path.join(out_dir, "repro")
    os.makedirs(os.path.join(repro, "scenes"), exist_ok=True)
    with open(path, "rb") as handle:
        data = handle.read()
    digest = fnv1a64(data)
    if info.get("hash") and info["hash"] != digest:
        notes.append(f"the suite file changed since the run (hash now {digest}, "
                     f"run {info['hash']}): the copy is today's file")
    target = os.path.join(repro, os.path.basename(path))
    shutil.copyfile(path, target)
    files.append(("suite " + os.path.basename(path), os.path.relpath(target, out_dir)))
    base = os.path.dirname(path)
    for rel in _scene_files(data.decode("utf-8", "replace")):
        source = os.path.normpath(os.path.join(base, rel))
        if not os.path.isfile(source):
            notes.append(f"scene file {rel} not found: not copied")
            continue
        target = os.path.join(repro, "scenes", os.path.basename(source))
        shutil.copyfile(source, target)
        files.append((f"scene {rel}", os.path.relpath(target, out_dir)))
    return {"files": files, "notes": notes}


def command_lines(meta, results_dir):
    """The commands that reproduce the results and the report."""
    if meta.get("command"):
        bench = str(meta["command"])
    else:
        info = _suite_info(meta)
        options = meta.get("options") if isinstance(meta.get("options"), dict) else {}
        suite = info.get("path") or "SUITE.yaml"
        jobs = options.get("jobs", meta.get("jobs"))
        bench = f"build/bench/quasiroll bench --suite {suite} --out {results_dir}"
        if jobs:
            bench += f" --jobs {jobs}"
        if options.get("filter") or meta.get("filter"):
            bench += f" --filter '{options.get('filter') or meta.get('filter')}'"
    return [bench, f"build/bench/quasiroll report {results_dir}"]


def environment():
    """The report generator's own environment."""
    return [("Python", f"{platform.python_version()} ({sys.executable})"),
            ("matplotlib", matplotlib.__version__), ("numpy", np.__version__),
            ("report generated on", f"{platform.node()}, {platform.platform()}")]
