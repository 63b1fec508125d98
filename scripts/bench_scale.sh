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

echo "load average before: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
printf '%-14s %7s %8s %8s %8s %7s %9s %9s %7s %11s %9s\n' config cases wall_s cases/s per_thr cpu_s cases/cpu_s maxRSS_MB files bytes bytes/case
run() {  # name yaml
  local name=$1 yaml=$2
  /usr/bin/time -v -o "$W/$name.time" "$TAILSIM" run "$yaml" --out "$W/$name" --threads "$THREADS" --quiet > "$W/$name.out"
  local cases wall rss files bytes cpu
  cases=$(sed -nE 's/^([0-9]+) cases: .*/\1/p' "$W/$name.out")
  wall=$(sed -nE 's/.* ([0-9.]+) s wall$/\1/p' "$W/$name.out")
  rss=$(sed -nE 's/.*Maximum resident set size \(kbytes\): ([0-9]+)/\1/p' "$W/$name.time")
  cpu=$(awk -F': ' '/User time|System time/ { s += $2 } END { print s }' "$W/$name.time")
  rm -f "$W/$name/.tailsim.lock"
  files=$(find "$W/$name" -type f | wc -l)
  bytes=$(du -sb "$W/$name" | cut -f1)
  awk -v n="$name" -v c="$cases" -v w="$wall" -v r="$rss" -v f="$files" -v b="$bytes" -v t="$THREADS" -v u="$cpu" 'BEGIN {
    printf "%-14s %7d %8.3f %8.0f %8.0f %7.2f %9.0f %9.1f %7d %11d %9.0f\n", n, c, w, c / w, c / w / t, u, c / u, r / 1024, f, b, b / c }'
  echo "$name $cases $wall $cpu" >> "$W/rates"
}
run analytic_none configs/scale/sweep5k_none.yaml
run analytic_thin configs/scale/sweep5k_thin.yaml
run analytic_full configs/scale/sweep5k_full.yaml
run mujoco_none configs/scale/mujoco40_none.yaml
[ "$BIG" = --big ] && run analytic_100k configs/scale/sweep100k_none.yaml

echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
awk -v t="$THREADS" '{ rate[$1] = $2 / $3 / t; cpu[$1] = $2 / $4 } END {
  printf "\nnone vs full (analytic, 5,000 cases, %d threads): %.2fx the cases/s; thin vs full: %.2fx\n", t,
         rate["analytic_none"] / rate["analytic_full"], rate["analytic_thin"] / rate["analytic_full"]
  printf "projected wall time, none output (measured per-thread rate x cores | cases per CPU second x cores):\n"
  split("2 16 64", cores, " ")
  for (i = 1; i <= 3; ++i)
    printf "  %2d cores: 10^6 analytic %7.0f s | %7.0f s;  10^5 MuJoCo %7.0f s | %7.0f s\n", cores[i],
           1e6 / (rate["analytic_none"] * cores[i]), 1e6 / (cpu["analytic_none"] * cores[i]),
           1e5 / (rate["mujoco_none"] * cores[i]), 1e5 / (cpu["mujoco_none"] * cores[i])
}' "$W/rates"
