#!/usr/bin/python3
"""Fails when the harness or the report names a backend in its code (issue
#20: backends carry their own knowledge in their BackendInfo; ctest
backend_names).

    scripts/check-backend-names.py QUASIROLL [ROOT]

The backend names are the registered ones (`QUASIROLL list --json`), so a
new backend is covered without editing this file. Searched: every
git-tracked .cc/.h/.py/.js file below bench/ and reports/, except the
places that name backends on purpose: tests (reports/test_*.py, the report
fixture generator reports/make_fixture.py) and the micro-benchmarks
(bench/micro/, which measure named configurations). Suites and scenes are
data, not code. A quoted name ("newton" or 'newton') is a hit. Exit 1
listing each hit, 0 otherwise.
"""
import json
import os
import re
import subprocess
import sys

from source_checks import default_root, tracked_files, verdict

EXEMPT = re.compile(r"^(bench/micro/|reports/test_[^/]*\.py$|reports/make_fixture\.py$)")
CODE = re.compile(r"\.(cc|h|py|js)$")


def main(argv):
    if not argv:
        print(__doc__, file=sys.stderr)
        return 2
    cli = argv[0]
    root = argv[1] if len(argv) > 1 else default_root(__file__)
    listing = json.loads(subprocess.run([cli, "list", "--json"], capture_output=True,
                                        text=True, check=True).stdout)
    names = sorted({b["name"] for kind in ("nlp", "dae") for b in listing[kind]})
    quoted = re.compile("|".join(f"[\"']{re.escape(n)}[\"']" for n in names))
    files = tracked_files(root, "bench", "reports")
    hits = []
    for path in files:
        if not CODE.search(path) or EXEMPT.match(path):
            continue
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
            for number, line in enumerate(f, 1):
                if quoted.search(line):
                    hits.append(f"{path}:{number}: {line.strip()}")
    return verdict(hits, f"check-backend-names: {len(hits)} line(s) name a backend "
                         f"({', '.join(names)})",
                   f"check-backend-names: no backend name in bench/ or reports/ code "
                   f"({len(names)} backends)")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
