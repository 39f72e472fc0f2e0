#!/usr/bin/python3
"""Fails when a folder includes a project header it may not (the layers of
docs/architecture.md; ctest layers).

    scripts/check-layers.py [ROOT]

Reads the `#include "quasiroll/<folder>/..."` lines of every git-tracked
.cc/.h file in the folders below and checks them against ALLOWED. Exit 1
listing each offending line, 0 otherwise.
"""
import os
import re
import sys

from source_checks import default_root, tracked_files, verdict

# folder -> the project folders it may include (besides itself).
ALLOWED = {
    "core": set(),
    "solvers": {"core"},
    "integrators": {"core"},
    "bench/io": {"core"},
    "bench/harness": {"core", "bench/io"},
    "bench/cluster": {"core", "bench/io", "bench/harness", "bench/atlas"},
    "bench/atlas": {"core", "bench/io"},
    "bench/cli": {"core", "bench/io", "bench/harness", "bench/cluster",
                  "bench/atlas"},
    "bench/python": {"core", "bench/io", "bench/harness"},
    "bench/micro": {"core", "bench/io", "bench/harness", "solvers", "integrators",
                    "conformance"},
    "tests/conformance": {"core", "conformance"},
}
INCLUDE = re.compile(r'#include\s+[<"]quasiroll/([a-z_]+)/(?:([a-z_]+)/)?')


def folder_of(path):
    for folder in sorted(ALLOWED, key=len, reverse=True):
        if path.startswith(folder + "/"):
            return folder
    return None


def included_folder(match):
    top, sub = match.group(1), match.group(2)
    if top == "bench" and sub:
        return f"bench/{sub}"
    return top


def main(argv):
    root = argv[0] if argv else default_root(__file__)
    files = tracked_files(root, "*.cc", "*.h")
    bad = []
    for path in files:
        folder = folder_of(path)
        if folder is None:
            continue
        own = "conformance" if folder == "tests/conformance" else folder
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
            for number, line in enumerate(f, 1):
                m = INCLUDE.search(line)
                if not m:
                    continue
                target = included_folder(m)
                if target != own and target not in ALLOWED[folder]:
                    bad.append(f"{path}:{number}: {folder} may not include {target}: "
                               f"{line.strip()}")
    return verdict(bad, f"check-layers: {len(bad)} include(s) against docs/architecture.md",
                   f"check-layers: every include of {len(ALLOWED)} folders follows the layers")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
