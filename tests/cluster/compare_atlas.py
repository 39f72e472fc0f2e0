#!/usr/bin/env python3
"""Are two atlas output directories the same atlas? (docs/cluster.md)

compare_atlas.py A B: atlas.csv and edge.csv (if either has one) equal row
for row and column for column except `wall_s` (timing), and meta.json's
`key` equal. Exit 0 if so, else 1 naming the first difference."""
import csv
import json
import os
import sys


def rows(path):
    with open(path, newline="") as f:
        table = list(csv.reader(f))
    header = table[0]
    keep = [i for i, name in enumerate(header) if name != "wall_s"]
    return [[r[i] for i in keep] for r in table]


def same_table(a, b, name):
    pa, pb = os.path.join(a, name), os.path.join(b, name)
    if not os.path.exists(pa) and not os.path.exists(pb):
        return True
    if not (os.path.exists(pa) and os.path.exists(pb)):
        print(f"compare_atlas: {name} only in one of {a}, {b}")
        return False
    ra, rb = rows(pa), rows(pb)
    if len(ra) != len(rb):
        print(f"compare_atlas: {name}: {len(ra)} vs {len(rb)} lines")
        return False
    for k, (x, y) in enumerate(zip(ra, rb)):
        if x != y:
            print(f"compare_atlas: {name} line {k + 1} differs:\n  {x}\n  {y}")
            return False
    return True


def main(a, b):
    ka = json.load(open(os.path.join(a, "meta.json")))["key"]
    kb = json.load(open(os.path.join(b, "meta.json")))["key"]
    if ka != kb:
        print(f"compare_atlas: meta.json keys differ: {ka} vs {kb}")
        return 1
    ok = same_table(a, b, "atlas.csv") and same_table(a, b, "edge.csv")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
