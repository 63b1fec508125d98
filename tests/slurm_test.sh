#!/usr/bin/env bash
# The Slurm path for real. Starts a single-node Slurm cluster in a temporary folder
# (scripts/slurm/local_cluster.sh: munged, slurmctld, slurmd, generated slurm.conf), submits a sweep
# as a job array + dependent merge (scripts/slurm/submit.sh), waits, and compares the merged folder
# with a single-process run (scripts/compare_folders.py). Needs root and Debian's slurm-wlm + munge.
# usage: slurm_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "$1" && pwd); bin=$(cd "$2" && pwd)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tailsim-slurm-XXXXXX")
cleanup() { "$src/scripts/slurm/local_cluster.sh" stop "$tmp/cluster" || true; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; [ -d "$tmp/cluster/log" ] && tail -n 20 "$tmp"/cluster/log/*.log >&2; exit 1; }
eval "$("$src/scripts/slurm/local_cluster.sh" start "$tmp/cluster")" || fail "could not start the local Slurm cluster"
export SLURM_CONF
exp="$src/configs/paper/fig11_wss.yaml"
"$bin/tailsim" run "$exp" --out "$tmp/single" --quiet --threads 2 --no-render >/dev/null
out=$(TAILSIM="$bin/tailsim" "$src/scripts/slurm/submit.sh" "$exp" "$tmp/sweep" 3) || fail "submit.sh"
echo "$out"
merge_job=$(echo "$out" | sed -n 's/.*merge: job \([0-9]*\).*/\1/p')
for _ in $(seq 600); do
  [ -z "$(squeue -h 2>/dev/null)" ] && break
  sleep 0.5
done
[ -z "$(squeue -h)" ] || fail "jobs still queued after 5 min: $(squeue)"
state=$(sacct -n -j "$merge_job" -o State 2>/dev/null | head -1 | tr -d ' ' || true)
[ -d "$tmp/sweep/merged" ] || fail "no merged folder (merge job $merge_job $state); logs: $(cat "$tmp"/sweep/logs/* 2>/dev/null | tail -20)"
python3 "$src/scripts/compare_folders.py" "$tmp/single" "$tmp/sweep/merged" || fail "the Slurm sweep differs from one run"
echo "ok: Slurm job array of 3 shards + dependent merge: identical to a single run"
echo PASS
