"""What the tree checks run by ctest share (scripts/check-layers.py,
check-function-length.py, check-backend-names.py): the files git tracks and
the verdict. Imported, not run."""
import os
import subprocess
import sys


def default_root(script):
    """The repository of a script in scripts/."""
    return os.path.join(os.path.dirname(script), "..")


def tracked_files(root, *pathspecs):
    """The files git tracks below root that match the pathspecs."""
    return subprocess.run(["git", "-C", root, "ls-files", *pathspecs],
                          capture_output=True, text=True, check=True).stdout.split()


def verdict(findings, failure, success):
    """Prints each finding; then exit code 1 with `failure` on stderr if there
    are any, else 0 with `success`."""
    for finding in findings:
        print(finding)
    if findings:
        print(failure, file=sys.stderr)
        return 1
    print(success)
    return 0
