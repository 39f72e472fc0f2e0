#!/usr/bin/python3
"""Fails when a C++ function body is longer than the limit (issue #20: no
function over 120 lines; ctest function_length, CI).

    scripts/check-function-length.py [ROOT] [--limit N]

Reads every git-tracked .cc/.h below ROOT (default: the repository). A
function is a brace block at namespace or class scope whose head has a
parameter list (lambdas and blocks inside a function count towards it); its
length runs from the first line of its head to its closing brace. Comments,
string and character literals and preprocessor lines are blanked first, so
braces inside them do not count. Exit 1 listing each offender
("path:line: N lines: head"), 0 otherwise.
"""
import os
import re
import sys

from source_checks import default_root, tracked_files, verdict

CONTROL = re.compile(r"^(if|for|while|switch|catch|do|else)\b")
SCOPE = re.compile(r"\b(namespace|class|struct|union|enum)\b[^()]*$")


def blank_literals(text):
    """text with comments and literals replaced by blanks, newlines kept."""
    out, i, n = [], 0, len(text)
    while i < n:
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
            continue
        if text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
            continue
        raw = re.match(r'R"([^(\s]*)\(', text[i:i + 20]) if text[i] == "R" else None
        if raw and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            end = ")" + raw.group(1) + '"'
            j = text.find(end, i)
            j = n if j < 0 else j + len(end)
            out.append('""' + "\n" * text.count("\n", i, j))
            i = j
            continue
        c = text[i]
        if c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum():  # 1'000 separator
                out.append(c)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def function_spans(text):
    """(first line, last line) of each function body at namespace/class scope."""
    s = blank_literals(text)
    stack, spans = [], []
    head_start, i, n = 0, 0, len(s)
    while i < n:
        c = s[i]
        if c == "#" and (i == 0 or s[i - 1] == "\n"):
            j = s.find("\n", i)
            while j > 0 and s[j - 1] == "\\":
                j = s.find("\n", j + 1)
            i = n if j < 0 else j
            head_start = i
            continue
        if c == "{":
            head = s[head_start:i]
            stripped = head.strip()
            kind = "block"
            if "function" not in stack:
                if SCOPE.search(stripped) or stripped.startswith("extern"):
                    kind = "scope"
                elif ")" in stripped and not CONTROL.match(stripped) \
                        and not stripped.endswith("="):
                    kind = "function"
            first = s.count("\n", 0, head_start + len(head) - len(head.lstrip())) + 1
            stack.append(kind)
            stack.append(first)
            head_start = i + 1
        elif c == "}":
            if stack:
                first = stack.pop()
                kind = stack.pop()
                if kind == "function":
                    spans.append((first, s.count("\n", 0, i) + 1))
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
        i += 1
    return spans


def main(argv):
    limit = 120
    args = list(argv)
    if "--limit" in args:
        k = args.index("--limit")
        limit = int(args[k + 1])
        del args[k:k + 2]
    root = args[0] if args else default_root(__file__)
    files = tracked_files(root, "*.cc", "*.h")
    offenders = []
    for path in files:
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
            text = f.read()
        lines = text.split("\n")
        for first, last in function_spans(text):
            length = last - first + 1
            if length > limit:
                offenders.append((length, path, first, lines[first - 1].strip()[:80]))
    return verdict([f"{path}:{first}: {length} lines: {head}"
                    for length, path, first, head in sorted(offenders, reverse=True)],
                   f"check-function-length: {len(offenders)} function(s) over {limit} lines",
                   f"check-function-length: no function over {limit} lines in "
                   f"{len(files)} files")


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
