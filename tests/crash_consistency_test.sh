#!/usr/bin/env bash
# Crash consistency (issue 16): a multi-case analytic sweep killed with SIGKILL at seeded random
# moments, then run to completion, gives the same result folder as one uninterrupted run: every
# file byte for byte, except the wall-clock fields ("wall_time_s"). No temporary file is left.
# Usage: crash_consistency_test.sh SOURCE_DIR BINARY_DIR [SEED]
set -euo pipefail
SRC=$1 BIN=$2
RANDOM=${3:-16}  # seeds bash's generator: the kill moments are reproducible
TAILSIM=$BIN/tailsim
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_crash.XXXXXX")
trap 'rm -rf "$W"' EXIT
cat > "$W/sweep.yaml" <<YAML
name: crash_sweep
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {range: [0.05, 0.95, 0.005]}}
models: [analytic]
output: {sample_dt_s: 0.0005}
YAML
now_ms() { date +%s%3N; }
t0=$(now_ms)
"$TAILSIM" run "$W/sweep.yaml" --out "$W/fresh" --quiet --threads 2 > /dev/null
T=$(( $(now_ms) - t0 ))
[ "$T" -ge 1 ] || T=1
echo "fresh run: ${T} ms"

kills=0
for i in 1 2 3 4 5 6; do
  delay=$(( RANDOM % (T * 2 / 3 + 1) ))
  "$TAILSIM" run "$W/sweep.yaml" --out "$W/crashed" --quiet --threads 2 > /dev/null 2>&1 &
  pid=$!
  sleep "$(printf '0.%03d' "$delay")"
  if kill -9 "$pid" 2>/dev/null; then kills=$((kills + 1)); fi
  wait "$pid" 2>/dev/null || true
  n=$( (find "$W/crashed/cases" -name result.json 2>/dev/null || true) | wc -l)
  echo "kill $i after ${delay} ms: $n cases finished"
done
"$TAILSIM" run "$W/sweep.yaml" --out "$W/crashed" --quiet --threads 2 > "$W/final.txt"
cat "$W/final.txt" | head -1
echo "$kills runs killed"

# No temporary file survives the final run.
if find "$W/crashed" -name '*.tmp.*' | grep -q .; then
  echo "FAIL: temporary files left:"; find "$W/crashed" -name '*.tmp.*'; exit 1
fi
# Every file equal to the fresh run's, wall times aside (JSON is written one key per line).
for d in fresh crashed; do
  cp -r "$W/$d" "$W/cmp_$d"
  rm -f "$W/cmp_$d/.tailsim.lock"
  find "$W/cmp_$d" -name '*.json' -exec sed -i -E 's/"wall_time_s": [-0-9.eE+]+/"wall_time_s": W/' {} +
  python3 - "$W/cmp_$d/results.csv" <<'PY'  # results.csv: its wall_time_s column
import csv, sys
rows = list(csv.reader(open(sys.argv[1], newline='')))
i = rows[0].index('wall_time_s')
for r in rows[1:]: r[i] = 'W'
csv.writer(open(sys.argv[1], 'w', newline=''), lineterminator='\n').writerows(rows)
PY
done
if ! diff -r "$W/cmp_fresh" "$W/cmp_crashed" > "$W/diff.txt"; then
  echo "FAIL: the resumed result folder differs from the fresh one:"; head -20 "$W/diff.txt"; exit 1
fi
echo "$(find "$W/cmp_fresh" -type f | wc -l) files identical (wall times aside)"
[ "$kills" -ge 1 ] || { echo "FAIL: no run was killed mid-way (the sweep finished too fast)"; exit 1; }
echo "crash consistency: ok"
