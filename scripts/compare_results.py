#!/usr/bin/env python3
"""Compare two result folders (one experiment or a suite): every summary field of every run, wall
times aside, and every time-series CSV cell by cell by column NAME (the same set of columns, each
column's text identical; the order of the columns may differ: issue 10 gave both models' CSVs one
column order).  usage: compare_results.py BASE NEW [--tol-deg X]
Exit 0 when identical (or within --tol-deg for summary fields ending in _deg), 1 otherwise."""
import csv, glob, json, os, sys
base, new = sys.argv[1], sys.argv[2]
tol = float(sys.argv[sys.argv.index('--tol-deg') + 1]) if '--tol-deg' in sys.argv else 0.0

def runs(root):
    out = {}
    files = glob.glob(os.path.join(root, 'summary.json')) or glob.glob(os.path.join(root, '*', 'summary.json'))
    for f in sorted(files):
        d = os.path.dirname(f)
        for c in json.load(open(f))['cases']:
            for m, r in c['runs'].items():
                r = dict(r); r.pop('wall_time_s', None)
                out[(os.path.basename(d), c['name'], m)] = (r, os.path.join(d, 'cases', c['dir'], m + '.csv'))
    return out

def columns(path):  # {name: [cell text, ...]} exactly as written
    rows = list(csv.reader(open(path, newline='')))
    return {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])} if rows else {}

def flat(d, p=''):
    for k, v in d.items():
        if isinstance(v, dict): yield from flat(v, p + k + '.')
        else: yield p + k, v

a, b = runs(base), runs(new)
bad = 0; maxd = 0.0; reordered = 0
for k in sorted(set(a) | set(b)):
    if k not in a or k not in b:
        print('only in one:', k); bad += 1; continue
    fa, fb = dict(flat(a[k][0])), dict(flat(b[k][0]))
    for f in sorted(set(fa) | set(fb)):
        va, vb = fa.get(f), fb.get(f)
        if va == vb: continue
        if isinstance(va, float) and isinstance(vb, float) and f.endswith('_deg') and abs(va - vb) <= tol:
            maxd = max(maxd, abs(va - vb)); continue
        print('differs:', k, f, va, vb); bad += 1
    ca, cb = a[k][1], b[k][1]
    if os.path.exists(ca):
        if not os.path.exists(cb):
            print('time series missing:', k); bad += 1; continue
        ta, tb = columns(ca), columns(cb)
        if ta != tb:
            diff = sorted(set(ta) ^ set(tb)) or [c for c in ta if ta[c] != tb[c]]
            print('time series differs:', k, 'columns', diff[:5]); bad += 1
        elif list(ta) != list(tb):
            reordered += 1
print(f'{len(a)} runs compared, {bad} differences, {reordered} time series with the same columns in another '
      f'order, max |d| of _deg fields within tol: {maxd:g}')
sys.exit(1 if bad else 0)
