#!/usr/bin/env bash
# A result folder stands alone: it holds the robot file (built-in ones too), an
# experiment.yaml naming that copy (comments kept), one MJCF per distinct MuJoCo model, and a
# results.csv that matches summary.json. Copied to another directory, with the robot file under
# configs/ edited afterwards, it re-runs to the same files (wall times aside), and its report does
# not change when the live robot file does.
# Usage: folder_reproduce_test.sh SOURCE_DIR BINARY_DIR
set -euo pipefail
SRC=$1 BIN=$2
TAILSIM=$BIN/tailsim
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_folder.XXXXXX")
trap 'rm -rf "$W"' EXIT

# A private configs/ tree: four paper experiments (a 6-link case, a pose sweep, a trajectory sweep
# with both models, a sweep over the number of links) and one on the built-in robot with a failing
# MuJoCo run, in a suite.
mkdir -p "$W/configs/paper" "$W/configs/robots"
cp "$SRC/configs/robots/paper_quadruped.yaml" "$W/configs/robots/"
for f in fig06b_model_comparison_6dof fig08_moment_contributions fig11_wss fig14_tail_dof; do
  cp "$SRC/configs/paper/$f.yaml" "$W/configs/paper/"
done
cat > "$W/configs/paper/builtin.yaml" <<'YAML'
# the built-in robot, quoted, with a comment after it
name: builtin_robot
robot: "paper"   # the packaged robot: copied too
tail: {links: 2}
trajectory: {theta0_deg: 30, dtheta_deg: -60, dT_s: 0.3, w_ss: 0.5}
mujoco: {max_tilt_deg: {sweep: [0.001, 30]}}   # 0.001: the MuJoCo run fails (tilt limit)
models: [analytic, mujoco]
YAML
cat > "$W/configs/paper/suite.yaml" <<'YAML'
experiments: [fig06b_model_comparison_6dof.yaml, fig08_moment_contributions.yaml, fig11_wss.yaml,
              fig14_tail_dof.yaml, builtin.yaml]
YAML

run() {  # exit 3 = some model run failed (the built-in experiment's tilt case): expected
  local rc=0
  "$TAILSIM" run "$@" --quiet --threads 2 > /dev/null || rc=$?
  [ "$rc" = 0 ] || [ "$rc" = 3 ] || { echo "FAIL: tailsim run $* exited $rc" >&2; exit 1; }
}
run "$W/configs/paper/suite.yaml" --out "$W/A"

python3 - "$W" <<'PY'
import csv, glob, json, os, sys
W = sys.argv[1]; A = os.path.join(W, 'A')
fail = lambda why: sys.exit('FAIL: ' + why)
members = sorted(os.path.dirname(p) for p in glob.glob(os.path.join(A, '*', 'summary.json')))
if len(members) != 5: fail(f'{len(members)} members, want 5')
suite_rows = 0
for d in members:
    s = json.load(open(os.path.join(d, 'summary.json')))
    src = open(s['source']).read()
    # experiment.yaml: the source with the value of robot: replaced, nothing else
    exp = open(os.path.join(d, 'experiment.yaml')).read()
    old = 'robot: "paper"' if 'builtin' in s['source'] else 'robot: ../robots/paper_quadruped.yaml'
    if src.count(old) != 1 or exp != src.replace(old, 'robot: robot.yaml'):
        fail(f'{d}/experiment.yaml is not the source with robot: robot.yaml')
    robot = open(os.path.join(d, 'robot.yaml')).read()
    if robot != open(os.path.join(W, 'configs/robots/paper_quadruped.yaml')).read():
        fail(f'{d}/robot.yaml is not a copy of the robot file')
    # one MJCF per distinct model, named by every case that ran MuJoCo
    named = set()
    for c in s['cases']:
        if 'mujoco' in c['runs']:
            m = c.get('mjcf')
            if not m or not os.path.isfile(os.path.join(d, m)): fail(f'{d} case {c["name"]}: no MJCF file {m}')
            rj = json.load(open(os.path.join(d, 'cases', c['dir'], 'result.json')))
            if rj.get('mjcf') != m: fail(f'{d} case {c["name"]}: result.json does not name {m}')
            named.add(m)
    files = {os.path.relpath(p, d) for p in glob.glob(os.path.join(d, 'mjcf', '*.xml'))}
    want = {'fig06b_model_comparison_6dof': 1, 'fig08_moment_contributions': 0, 'fig11_wss': 1,
            'fig14_tail_dof': 6, 'builtin_robot': 1}[s['experiment']]
    if files != named or len(files) != want:
        fail(f'{d}: MJCF files {sorted(files)}, named {sorted(named)}, want {want} distinct')
    # results.csv against summary.json, run by run
    with open(os.path.join(d, 'results.csv'), newline='') as f:
        rows = list(csv.DictReader(f))
    byk = {(r['experiment'], r['case'], r['model']): r for r in rows}
    runs = [(c, m, r) for c in s['cases'] for m, r in c['runs'].items()]
    if len(rows) != len(runs) or len(byk) != len(rows): fail(f'{d}/results.csv: {len(rows)} rows for {len(runs)} runs')
    suite_rows += len(rows)
    for c, m, r in runs:
        row = byk[(s['experiment'], c['name'], m)]
        for k in s['swept_keys']:
            if float(row[k]) != float(c['sweep'][k]): fail(f'{d} {c["name"]}: {k} {row[k]} != {c["sweep"][k]}')
        num = lambda v: '' if v is None else v
        for k in ('phi_net_deg', 't_stop_s', 'stick_slip_events', 'solver_steps', 'wall_time_s'):
            v = r.get(k)
            if (row[k] == '') != (v is None) or (v is not None and float(row[k]) != v):
                fail(f'{d} {c["name"]} {m}: {k} {row[k]!r} != {v!r}')
        if row['ok'] != ('true' if r['ok'] else 'false'): fail(f'{d} {c["name"]} {m}: ok {row["ok"]}')
        if row['error'] != r.get('error', ''): fail(f'{d} {c["name"]} {m}: error {row["error"]!r}')
        if not r['ok'] and row['phi_net_deg'] != '': fail(f'{d} {c["name"]} {m}: a failed run has a phi_net')
        if row['warnings'] != '; '.join(r['warnings']): fail(f'{d} {c["name"]} {m}: warnings')
        for k, v in r.get('extra', {}).items():
            if (row[k] == '') != (v is None) or (v is not None and float(row[k]) != v):
                fail(f'{d} {c["name"]} {m}: extra {k} {row[k]!r} != {v!r}')
# both models' time series share one column order: the common columns first, in the same positions
shared_checked = 0
for d in members:
    for case in glob.glob(os.path.join(d, 'cases', '*')):
        ha, hm = (os.path.join(case, m + '.csv') for m in ('analytic', 'mujoco'))
        if not (os.path.exists(ha) and os.path.exists(hm)): continue
        ca, cm = (next(csv.reader(open(h, newline=''))) for h in (ha, hm))
        common = [c for c in ca if c in cm]
        if ca[:len(common)] != common or cm[:len(common)] != common:
            fail(f'{case}: the columns both models write are not first in one order: {ca} / {cm}')
        shared_checked += 1
if shared_checked < 10: fail(f'only {shared_checked} cases with both models')
with open(os.path.join(A, 'results.csv'), newline='') as f:
    if len(list(csv.DictReader(f))) != suite_rows: fail('the suite results.csv does not hold every member row')
if not any(r == 'false' for d in members for r in (x['ok'] for x in csv.DictReader(open(os.path.join(d, 'results.csv'))))):
    fail('no failed run in the results (the tilt case should fail)')
print(f'{len(members)} members: experiment.yaml, robot.yaml, mjcf/ and results.csv ({suite_rows} rows) checked')
PY

# Copy the folder elsewhere, report it, then change the live robot file.
mkdir -p "$W/moved"
cp -r "$W/A" "$W/moved/A"
"$TAILSIM" report "$W/moved/A" > /dev/null
cp "$W/moved/A/report.md" "$W/report_before.md"
sed -i 's/^\(  mass_kg:\) *[0-9.]*/\1 9.5/' "$W/configs/robots/paper_quadruped.yaml"
cmp -s "$SRC/configs/robots/paper_quadruped.yaml" "$W/configs/robots/paper_quadruped.yaml" &&
  { echo "FAIL: the robot file edit changed nothing" >&2; exit 1; }
"$TAILSIM" report "$W/moved/A" > /dev/null
cmp "$W/report_before.md" "$W/moved/A/report.md" ||
  { echo "FAIL: the copy's report changed with the live robot file" >&2; exit 1; }

# The live configs now give other results (so the edit matters) ...
run "$W/configs/paper/suite.yaml" --out "$W/live"
# ... while the copy re-runs to its own results, every file equal but for wall times.
run "$W/moved/A/experiment.yaml" --out "$W/B"
python3 - "$W/A" "$W/B" "$W/live" <<'PY'
import csv, io, json, os, sys
A, B, live = sys.argv[1:4]
def files(root):
    out = set()
    for d, _, fs in os.walk(root):
        for f in fs:
            # (.tailsim-manifest hashes summary.json and results.csv, wall times included)
            if f not in ('.tailsim.lock', '.tailsim-manifest'): out.add(os.path.relpath(os.path.join(d, f), root))
    return out
def strip(v):  # JSON without its wall-clock fields
    if isinstance(v, dict): return {k: strip(x) for k, x in v.items() if k != 'wall_time_s'}
    if isinstance(v, list): return [strip(x) for x in v]
    return v
def table(p):  # results.csv without its wall-clock column
    rows = list(csv.reader(open(p, newline='')))
    i = rows[0].index('wall_time_s')
    return [r[:i] + r[i + 1:] for r in rows]
def same(a, b, rel):
    if rel.endswith('.json'): return strip(json.load(open(a))) == strip(json.load(open(b)))
    if rel.endswith('results.csv'): return table(a) == table(b)
    return open(a, 'rb').read() == open(b, 'rb').read()
fa, fb = files(A) - {'report.md'}, files(B)
if fa != fb: sys.exit(f'FAIL: files only in one: {sorted(fa ^ fb)[:10]}')
diff = [r for r in sorted(fa) if not same(os.path.join(A, r), os.path.join(B, r), r)]
if diff: sys.exit(f'FAIL: the re-run from the copy differs in {len(diff)} files: {diff[:10]}')
if table(os.path.join(A, 'results.csv')) == table(os.path.join(live, 'results.csv')):
    sys.exit('FAIL: the edited robot file changed no result (the test could not tell)')
print(f're-run from the copy: {len(fa)} files identical (wall times aside); the live configs now differ')
PY
echo "folder_reproduce: OK"
