#!/usr/bin/python3
"""Every citation of the model resolves in docs/model.md (issue #17).

Scans the tracked text files of the repository (git ls-files) for
  * `model.md §x.y` (also `model.md §x`, ranges `§1–§6`, lists `§1.2, §1.3`
    and `model §x.y`): each section number must be a heading of
    docs/model.md ("## x." or "### x.y");
  * oracle ids O1 … O8 with their suffixes (O2b, O3-num, ...): each must be a
    row of the oracle table of model.md §9.1 ("| O3-num |");
  * citations of documents users never see: "model-notes", "model notes",
    "notes §", "the notes", "Appendix A".
Prints one line per problem (file:line: ...) and exits 1 if there is any.
    scripts/check-model-refs.py [REPO_DIR]
    scripts/check-model-refs.py --self-test   (the check itself catches errors)
"""
import os
import re
import subprocess
import sys
import tempfile


def self_test():
    """The check fails on what it must fail on: a temporary repository whose
    model.md has §1.1 and O1, and a file citing §1.1, §2.3, O1, O9 and
    model-notes, must give exactly three problems."""
    with tempfile.TemporaryDirectory() as d:
        os.makedirs(os.path.join(d, "docs"))
        with open(os.path.join(d, "docs", "model.md"), "w") as f:
            f.write("## 1. A\n\n### 1.1 B\n\n| id | x |\n|---|---|\n| O1 | y |\n")
        with open(os.path.join(d, "a.cc"), "w") as f:
            f.write("// model.md §1.1 and model.md §2.3; O1, O9; model-notes\n")
        subprocess.run(["git", "init", "-q", d], check=True)
        subprocess.run(["git", "-C", d, "add", "-A"], check=True)
        out = subprocess.run([sys.executable, os.path.abspath(__file__), d],
                             capture_output=True, text=True)
        lines = [l for l in out.stdout.splitlines() if l.startswith("a.cc:")]
        ok = (out.returncode == 1 and len(lines) == 3 and "§2.3" in lines[0]
              and "O9" in lines[1] and "not part of quasiroll" in lines[2])
        print(f"check-model-refs self-test: {'ok' if ok else 'FAILED'}")
        if not ok:
            print(out.stdout)
        return ok


if len(sys.argv) > 1 and sys.argv[1] == "--self-test":
    sys.exit(0 if self_test() else 1)

repo = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                       os.path.join(os.path.dirname(__file__), ".."))
model_path = os.path.join(repo, "docs", "model.md")
model = open(model_path, encoding="utf-8").read()

sections = set()
for m in re.finditer(r"^#{2,4} (\d+(?:\.\d+)*)\.?\s", model, re.M):
    sections.add(m.group(1))
oracles = set(re.findall(r"^\| (O\d+[a-z]?(?:-[a-z]+)?) \|", model, re.M))
if not sections or not oracles:
    sys.exit(f"check-model-refs: no numbered headings or oracle table in {model_path}")

files = subprocess.run(["git", "-C", repo, "ls-files", "-z"], capture_output=True,
                       check=True).stdout.decode().split("\0")
this = os.path.relpath(os.path.abspath(__file__), repo)
cite = re.compile(r"\bmodel(?:\.md)?,?\s+((?:§\s?\d+(?:\.\d+)*(?:\s*(?:–|-|,|and|,\s*and)\s*)?)+)")
number = re.compile(r"§\s?(\d+(?:\.\d+)*)")
oracle = re.compile(r"(?<![\w-])O\d+[a-z]?(?:-(?:paper|pvc|num))?(?![\w])")
forbidden = re.compile(r"model[- ]notes|\bnotes §|\bthe notes\b|\bAppendix A\b", re.I)

problems = []
checked = 0
for rel in files:
    if not rel or rel == this:
        continue
    path = os.path.join(repo, rel)
    try:
        text = open(path, encoding="utf-8").read()
    except (UnicodeDecodeError, IsADirectoryError, FileNotFoundError):
        continue  # binary files (images), submodules
    for lineno, line in enumerate(text.splitlines(), 1):
        where = f"{rel}:{lineno}"
        for m in cite.finditer(line):
            for n in number.findall(m.group(1)):
                checked += 1
                if n not in sections:
                    problems.append(f"{where}: model.md §{n} is not a section of docs/model.md")
        for m in oracle.finditer(line):
            checked += 1
            if m.group(0) not in oracles:
                problems.append(f"{where}: oracle {m.group(0)} is not defined in docs/model.md §9.1")
        if forbidden.search(line):
            problems.append(f"{where}: cites a document that is not part of quasiroll: {line.strip()[:100]}")

for p in problems:
    print(p)
print(f"check-model-refs: {checked} citations checked, {len(problems)} problems "
      f"({len(sections)} sections, {len(oracles)} oracles in docs/model.md)")
sys.exit(1 if problems else 0)
