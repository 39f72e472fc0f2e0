#!/usr/bin/python3
"""Comparison report for a quasiroll results directory.

    /usr/bin/python3 reports/make_report.py DIR [--out OUTDIR] [--strict]

Writes DIR/report/index.html (or OUTDIR/index.html) with every figure as PNG
and SVG beside it, and prints the absolute path of index.html last. Exit
codes: 0 success, 2 bad input (one line on stderr), 1 internal error.
See reports/README.md.
"""

import argparse
import os
import sys
import warnings

os.environ.setdefault("MPLBACKEND", "Agg")
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

PROG = "make_report"


def fail(message, code):
    print(f"{PROG}: {message}", file=sys.stderr)
    return code


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as one line on stderr, exit code 2."""

    def error(self, message):
        sys.exit(fail(f"{message} (usage: {PROG}.py DIR [--out OUTDIR])", 2))


def parse_args(argv):
    parser = OneLineParser(
        prog=PROG, description="Write the quasiroll comparison report (HTML + figures).")
    parser.add_argument("results_dir", metavar="DIR",
                        help="results directory holding runs.csv, trajectories/, meta.json")
    parser.add_argument("--out", metavar="OUTDIR",
                        help="output directory (default DIR/report)")
    parser.add_argument("--strict", action="store_true",
                        help="fail (exit 2) when a figure has no data, instead of "
                             "drawing a placeholder and listing a warning")
    parser.add_argument("--allow-missing", action="store_true",
                        help=argparse.SUPPRESS)  # the default; kept for scripts
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    try:
        import matplotlib  # noqa: F401
        import numpy  # noqa: F401
    except ImportError as exc:
        return fail(f"{exc.name} is not available to {sys.executable}; "
                    "run with /usr/bin/python3", 2)
    try:
        from quasiroll_report.data import ReportError
        from quasiroll_report.report import build_report
    except Exception as exc:  # noqa: BLE001 - e.g. no runs.csv schema installed
        return fail(f"internal error: {type(exc).__name__}: {exc}", 1)
    warnings.simplefilter("ignore")
    try:
        index = build_report(args.results_dir, args.out, not args.strict)
    except ReportError as exc:
        return fail(str(exc), 2)
    except Exception as exc:  # noqa: BLE001 - one line, never a traceback
        if os.environ.get("QUASIROLL_REPORT_DEBUG"):
            raise
        return fail(f"internal error: {type(exc).__name__}: {exc} "
                    "(set QUASIROLL_REPORT_DEBUG=1 for the traceback)", 1)
    print(index)
    return 0


if __name__ == "__main__":
    sys.exit(main())
