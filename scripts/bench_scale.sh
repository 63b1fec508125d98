#!/usr/bin/env bash
# Sweep throughput, memory and disk per case (issue 13, docs/scale.md "scale"):
#   1. 5,000 analytic cases on THREADS threads with output.time_series none, thin and full, one
#      after the other in this one run (their ratio is the output's cost);
#   2. 40 MuJoCo cases (none);
#   3. with --big: 100,000 analytic cases (none).
# For each: wall time (tailsim's own "s wall"), cases/s, cases/s per thread, max RSS and file-system
# output blocks (/usr/bin/time -v), files and bytes in the result folder, and the projected wall
# time of 10^6 analytic / 10^5 MuJoCo cases on 2, 16 and 64 cores (per-thread rate x cores).
# Usage: scripts/bench_scale.sh [BUILD_DIR] [THREADS] [--big]     (default build, 2)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
THREADS=${2:-2}
BIG=${3:-}
TAILSIM=$BUILD/tailsim
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_scale.XXXXXX")
trap 'rm -rf "$W"' EXIT

printf '%-16s %8s %9s %9s %11s %10s %8s %12s %10s\n' config cases wall_s cases/s per_thread maxRSS_MB files bytes bytes/case
run() {  # name yaml
  local name=$1 yaml=$2
  /usr/bin/time -v -o "$W/$name.time" "$TAILSIM" run "$yaml" --out "$W/$name" --threads "$THREADS" --quiet > "$W/$name.out"
  local cases wall rss files bytes
  cases=$(sed -nE 's/^([0-9]+) cases: .*/\1/p' "$W/$name.out")
  wall=$(sed -nE 's/.* ([0-9.]+) s wall$/\1/p' "$W/$name.out")
  rss=$(sed -nE 's/.*Maximum resident set size \(kbytes\): ([0-9]+)/\1/p' "$W/$name.time")
  rm -f "$W/$name/.tailsim.lock"
  files=$(find "$W/$name" -type f | wc -l)
  bytes=$(du -sb "$W/$name" | cut -f1)
  awk -v n="$name" -v c="$cases" -v w="$wall" -v r="$rss" -v f="$files" -v b="$bytes" -v t="$THREADS" 'BEGIN {
    printf "%-16s %8d %9.3f %9.0f %11.0f %10.1f %8d %12d %10.0f\n", n, c, w, c / w, c / w / t, r / 1024, f, b, b / c }'
  echo "$name $cases $wall" >> "$W/rates"
}
run analytic_none configs/scale/sweep5k_none.yaml
run analytic_thin configs/scale/sweep5k_thin.yaml
run analytic_full configs/scale/sweep5k_full.yaml
run mujoco_none configs/scale/mujoco40_none.yaml
[ "$BIG" = --big ] && run analytic_100k configs/scale/sweep100k_none.yaml

awk -v t="$THREADS" '{ rate[$1] = $2 / $3 / t } END {
  printf "\nnone vs full (analytic, 5,000 cases, %d threads): %.2fx the cases/s; thin vs full: %.2fx\n", t,
         rate["analytic_none"] / rate["analytic_full"], rate["analytic_thin"] / rate["analytic_full"]
  printf "projected wall time (per-thread rate x cores, none output):\n"
  split("2 16 64", cores, " ")
  for (i = 1; i <= 3; ++i)
    printf "  %2d cores: 10^6 analytic %8.0f s, 10^5 MuJoCo %8.0f s\n", cores[i], 1e6 / (rate["analytic_none"] * cores[i]),
           1e5 / (rate["mujoco_none"] * cores[i])
}' "$W/rates"
