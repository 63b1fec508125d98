#!/usr/bin/env bash
# Crash consistency: a multi-case analytic sweep killed with SIGKILL at seeded random
# moments, then run to completion, gives the same result folder as one uninterrupted run: every
# file byte for byte, except the wall-clock fields ("wall_time_s"). No temporary file is left.
# OUTPUT: full (default: a folder per case), none (no time series: no case folders, resume
# from DIR/cases.jsonl, whose last line is also torn by hand before the final run), or hdf5-thin
# (thin series in DIR/time_series.h5, compared through h5dump: the file's bytes may be laid out
# differently after a resume, its contents must not).
# Usage: crash_consistency_test.sh SOURCE_DIR BINARY_DIR [SEED] [OUTPUT]
set -euo pipefail
SRC=$1 BIN=$2
RANDOM=${3:-16}  # seeds bash's generator: the kill moments are reproducible
OUTPUT=${4:-full}
case "$OUTPUT" in
  full) OUT_YAML="{sample_dt_s: 0.0005}" ;;
  none) OUT_YAML="{sample_dt_s: 0.0005, time_series: none}" ;;
  hdf5-thin) OUT_YAML="{sample_dt_s: 0.0005, time_series: thin, time_series_file: hdf5}" ;;
  *) echo "unknown OUTPUT $OUTPUT"; exit 2 ;;
esac
TAILSIM=$BIN/tailsim
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_crash.XXXXXX")
trap 'rm -rf "$W"' EXIT
cat > "$W/sweep.yaml" <<YAML
name: crash_sweep
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {range: [0.05, 0.95, 0.005]}}
models: [analytic]
output: $OUT_YAML
YAML
now_ms() { date +%s%3N; }
t0=$(now_ms)
"$TAILSIM" run "$W/sweep.yaml" --out "$W/fresh" --quiet --threads 2 > /dev/null
T=$(( $(now_ms) - t0 ))
[ "$T" -ge 1 ] || T=1
echo "fresh run: ${T} ms"

kills=0
if [ "$OUTPUT" = hdf5-thin ]; then
  # One finished case published in time_series.h5 first: the killed runs and the final one must copy its
  # group from the published file (a case is resumed only when that file has its group with its key).
  "$TAILSIM" run "$W/sweep.yaml" --out "$W/crashed" --quiet --threads 2 --case w_ss=0.5 > /dev/null
  h5ls "$W/crashed/time_series.h5" | grep -q '^w_ss=0.5 ' || { echo "FAIL: w_ss=0.5 not in time_series.h5"; exit 1; }
fi
for i in 1 2 3 4 5 6; do
  delay=$(( RANDOM % (T * 2 / 3 + 1) ))
  "$TAILSIM" run "$W/sweep.yaml" --out "$W/crashed" --quiet --threads 2 > /dev/null 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay / 1000)) $((delay % 1000)))"  # delay in ms (may exceed 1 s)
  if kill -9 "$pid" 2>/dev/null; then kills=$((kills + 1)); fi
  wait "$pid" 2>/dev/null || true
  n=$( (find "$W/crashed/cases" -name result.json 2>/dev/null || true) | wc -l)
  [ -f "$W/crashed/cases.jsonl" ] && n=$(wc -l < "$W/crashed/cases.jsonl")
  echo "kill $i after ${delay} ms: $n cases finished"
done
if [ "$OUTPUT" != full ] && [ ! -f "$W/crashed/cases.jsonl" ]; then
  # Every kill came before the first case finished (a slow build: ASan starts much slower): one more
  # run, killed as soon as a case is in the journal, so the torn-line check below has a journal.
  "$TAILSIM" run "$W/sweep.yaml" --out "$W/crashed" --quiet --threads 2 > /dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1 1200); do
    [ -s "$W/crashed/cases.jsonl" ] && break
    sleep 0.05
  done
  if kill -9 "$pid" 2>/dev/null; then kills=$((kills + 1)); fi
  wait "$pid" 2>/dev/null || true
  echo "kill 7 after the first journal line: $(wc -l < "$W/crashed/cases.jsonl" 2>/dev/null || echo 0) cases finished"
fi
if [ "$OUTPUT" != full ]; then
  # A torn last line, as a kill inside the append leaves it: cut off, never read, never glued to the next line.
  [ -f "$W/crashed/cases.jsonl" ] || { echo "FAIL: no DIR/cases.jsonl after the killed runs"; exit 1; }
  printf '{"dir":"w_ss=0.5","experiment":"crash_sw' >> "$W/crashed/cases.jsonl"
  if [ -d "$W/crashed/cases" ]; then echo "FAIL: case folders created with output $OUTPUT"; exit 1; fi
fi
"$TAILSIM" run "$W/sweep.yaml" --out "$W/crashed" --quiet --threads 2 > "$W/final.txt"
cat "$W/final.txt" | head -1
echo "$kills runs killed"

# No temporary file survives the final run.
if find "$W/crashed" -name '*tmp.*' | grep -q .; then
  echo "FAIL: temporary files left:"; find "$W/crashed" -name '*tmp.*'; exit 1
fi
# Every file equal to the fresh run's, wall times aside (JSON is written one key per line).
for d in fresh crashed; do
  cp -r "$W/$d" "$W/cmp_$d"
  rm -f "$W/cmp_$d/.tailsim.lock"
  # The manifest hashes summary.json and results.csv, wall times included: it must name every file as
  # it is (checked), and is then left out of the comparison.
  (cd "$W/$d" && sha256sum --quiet -c .tailsim-manifest) || { echo "FAIL: $d/.tailsim-manifest does not match its files"; exit 1; }
  rm -f "$W/cmp_$d/.tailsim-manifest"
  find "$W/cmp_$d" -name '*.json' -exec sed -i -E 's/"wall_time_s": [-0-9.eE+]+/"wall_time_s": W/' {} +
  find "$W/cmp_$d" -name '*.jsonl' -exec sed -i -E 's/"wall_time_s":[-0-9.eE+]+/"wall_time_s":W/g' {} +
  if [ -f "$W/cmp_$d/time_series.h5" ]; then  # contents, not layout
    h5dump "$W/cmp_$d/time_series.h5" | sed 1d > "$W/cmp_$d/time_series.h5.txt"
    rm "$W/cmp_$d/time_series.h5"
  fi
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
if [ "$OUTPUT" != full ] && [ -d "$W/crashed/cases" ]; then echo "FAIL: case folders created with output $OUTPUT"; exit 1; fi
if [ "$OUTPUT" = none ] && [ "$(wc -l < "$W/crashed/cases.jsonl")" -ne "$(($(wc -l < "$W/crashed/results.csv") - 1))" ]; then
  echo "FAIL: cases.jsonl does not have one line per case"; exit 1
fi
[ "$kills" -ge 1 ] || { echo "FAIL: no run was killed mid-way (the sweep finished too fast)"; exit 1; }
echo "crash consistency: ok"
