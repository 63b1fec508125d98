#!/usr/bin/env bash
# A sweep split with `tailsim run --shard K/N`, run by GNU parallel (scripts/parallel_sweep.sh),
# and joined by `tailsim merge` gives the folder a single process writes (every file; wall times aside,
# scripts/compare_folders.py). Also a suite (the paper suite, 3 shards), and the merge's refusals.
# usage: shard_merge_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "$1" && pwd); bin=$(cd "$2" && pwd); tailsim="$bin/tailsim"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tailsim-shards-XXXXXX"); trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
ok() { echo "ok: $*"; }
cd "$tmp"
exp="$src/configs/paper/fig09_theta0_dQ2B.yaml"   # 49 cases, analytic + MuJoCo
"$tailsim" run "$exp" --out single --quiet --threads 2 >/dev/null
TAILSIM="$tailsim" "$src/scripts/parallel_sweep.sh" "$exp" par 4 >par.log 2>&1 || fail "parallel_sweep.sh: $(tail -5 par.log)"
python3 "$src/scripts/compare_folders.py" single par/merged || fail "4 shards by GNU parallel, merged, differ from one run"
n=$(for k in 1 2 3 4; do python3 -c "import json,sys; print(len(json.load(open(sys.argv[1]))['cases']))" par/shards/$k-of-4/summary.json; done | sort -n | tr '\n' ' ')
ok "fig09: 4 shards by GNU parallel (cases per shard: $n) merge identical to a single run"

# Without case folders (output.time_series none: DIR/cases.jsonl; thin in hdf5: DIR/time_series.h5).
for out in "{time_series: none}" "{time_series: thin, time_series_file: hdf5}"; do
  cat > nf.yaml <<YAML
name: nofolders
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: {range: [0, 90, 10]}, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.25, 0.5]}}
models: [analytic]
output: $out
YAML
  rm -rf nf_single nf1 nf2 nf3 nf_merged
  "$tailsim" run nf.yaml --out nf_single --quiet --threads 2 >/dev/null
  for k in 1 2 3; do "$tailsim" run nf.yaml --shard $k/3 --out nf$k --quiet --threads 2 >/dev/null; done
  "$tailsim" merge nf1 nf2 nf3 --out nf_merged >/dev/null
  [ ! -d nf_merged/cases ] || fail "$out: case folders in the merged folder"
  python3 "$src/scripts/compare_folders.py" nf_single nf_merged || fail "$out: 3 shards merged differ from one run"
  ok "output $out: 3 shards merged identical to a single run"
done

suite="$src/configs/paper/all.yaml"
"$tailsim" run "$suite" --out psingle --quiet --threads 2 >/dev/null
for k in 1 2 3; do "$tailsim" run "$suite" --shard $k/3 --out pshard$k --quiet --threads 2 >/dev/null; done
"$tailsim" merge pshard1 pshard2 pshard3 --out pmerged >/dev/null
python3 "$src/scripts/compare_folders.py" psingle pmerged || fail "paper suite: 3 shards merged differ from one run"
ok "paper suite: 3 shards merged identical to a single run"

# A missing shard, shards of different experiments, a non-empty --out: refused, nothing written.
rc=0; "$tailsim" merge pshard1 pshard2 --out pm2 2>err.txt || rc=$?
[ $rc -eq 1 ] && grep -q "finished in none of the shard folders" err.txt || fail "missing shard: rc $rc, $(cat err.txt)"
[ ! -e pm2 ] && [ -z "$(ls -d pm2.merge.tmp.* 2>/dev/null)" ] || fail "a failed merge left files"
rc=0; "$tailsim" merge par/shards/1-of-4 pshard1 --out pm3 2>err.txt || rc=$?
[ $rc -eq 1 ] && grep -q "not of the same run" err.txt || fail "mixed shards: rc $rc, $(cat err.txt)"
rc=0; "$tailsim" merge pshard1 pshard2 pshard3 --out single 2>err.txt || rc=$?
[ $rc -eq 1 ] && grep -q "not empty" err.txt || fail "non-empty --out: rc $rc, $(cat err.txt)"
rc=0; "$tailsim" run "$exp" --shard 5/4 --out bad 2>err.txt || rc=$?
[ $rc -ne 0 ] && grep -q "want K/N" err.txt && [ ! -e bad ] || fail "--shard 5/4: rc $rc, $(cat err.txt)"
ok "merge refuses a missing shard, mixed runs, a non-empty --out; --shard 5/4 refused"
echo PASS
