#!/usr/bin/env python3
"""Are two tailsim result folders the same, measured wall times aside?  usage: compare_folders.py A B [--other-build]
Every file under A and B (except .tailsim.lock and .tailsim-manifest) must exist in both; each
.tailsim-manifest must name its folder's files as they are (it hashes them, wall times included); JSON files are compared with every
"wall_time_s" removed (also each line of cases.jsonl), results.csv files without their wall_time_s column,
time_series.h5 by its h5dump listing (contents, not file layout), everything else byte for byte.
--other-build: A and B come from two builds (a change checked against the code before it): the JSON
files also without "key" (each case's key hashes the build) and "tailsim_git_commit".
Prints the differences and exits 1, or "identical: N files" and 0."""
import csv, hashlib, io, json, os, subprocess, sys

manifest_errors = []

def check_manifest(d):  # "<sha256>  <name>" lines: each file as it is now
    for line in open(os.path.join(d, ".tailsim-manifest")):
        digest, name = line.rstrip("\n").split("  ", 1)
        p = os.path.join(d, name)
        if not os.path.isfile(p) or hashlib.sha256(open(p, "rb").read()).hexdigest() != digest:
            manifest_errors.append(f"{d}/.tailsim-manifest: {name} is not as named")

def walk(root):
    out = set()
    for d, _, files in os.walk(root):
        for f in files:
            rel = os.path.relpath(os.path.join(d, f), root)
            if f == ".tailsim-manifest":
                check_manifest(d)
            elif f != ".tailsim.lock":
                out.add(rel)
    return out

skip = {"wall_time_s"} | ({"key", "tailsim_git_commit"} if "--other-build" in sys.argv else set())

def strip(j):
    if isinstance(j, dict):
        return {k: strip(v) for k, v in j.items() if k not in skip}
    if isinstance(j, list):
        return [strip(v) for v in j]
    return j

def table(path):
    rows = list(csv.reader(open(path, newline="")))
    if not rows:
        return rows
    drop = [i for i, h in enumerate(rows[0]) if h == "wall_time_s"]
    return [[c for i, c in enumerate(r) if i not in drop] for r in rows]

a, b = [x for x in sys.argv[1:] if x != "--other-build"][:2]
fa, fb = walk(a), walk(b)
bad = [f"only in {a}: {f}" for f in sorted(fa - fb)] + [f"only in {b}: {f}" for f in sorted(fb - fa)]
for rel in sorted(fa & fb):
    pa, pb = os.path.join(a, rel), os.path.join(b, rel)
    if rel.endswith(".json"):
        same = strip(json.load(open(pa))) == strip(json.load(open(pb)))
    elif rel.endswith(".jsonl"):
        same = [strip(json.loads(l)) for l in open(pa)] == [strip(json.loads(l)) for l in open(pb)]
    elif rel.endswith(".h5"):
        dump = lambda p: subprocess.run(["h5dump", p], capture_output=True, text=True, check=True).stdout.split("\n", 1)[1]
        same = dump(pa) == dump(pb)
    elif os.path.basename(rel) == "results.csv":
        same = table(pa) == table(pb)
    else:
        same = open(pa, "rb").read() == open(pb, "rb").read()
    if not same:
        bad.append(f"differs: {rel}")
bad = manifest_errors + bad
for line in bad[:30]:
    print(line)
if bad:
    print(f"{len(bad)} differences")
    sys.exit(1)
print(f"identical: {len(fa)} files (wall times aside)")
