#!/usr/bin/env bash
# Command-line refusals that happen before any work, one class per call, each registered as its own
# CTest test (tests/CMakeLists.txt):
#   mjcf-menagerie  `tailsim mjcf EXP --menagerie DIR` of a sweep with more distinct MuJoCo models
#                   than limits::kMaxMenagerieModels is refused with the estimate and the --case hint,
#                   and writes nothing.
#   merge-inside-shard  `tailsim merge A B --out A/sub` says the merged folder is inside a shard
#                   (it reported a suite in its own staging folder and suggested --fresh).
# Usage: command_bounds_test.sh SOURCE_DIR BINARY_DIR CLASS
set -uo pipefail
SRC=$1 BIN=$2 CLASS=$3
TAILSIM=$BIN/tailsim
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_bounds.XXXXXX")
trap 'rm -rf "$W"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

case "$CLASS" in
mjcf-menagerie)
  # 201 cases, each its own model (the tail base moves): one more than the limit.
  cat > "$W/mj.yaml" <<YAML
name: mj
robot: paper
trajectory: {dtheta_deg: -90, dT_s: 0.25}
models: [mujoco]
quadruped: {d_Q2B_m: {range: [0.05, 0.25, 0.001]}}
YAML
  rc=0
  timeout 60 "$TAILSIM" mjcf "$W/mj.yaml" --menagerie "$W/men" > "$W/out" 2> "$W/err" || rc=$?
  [ $rc -eq 1 ] || { cat "$W/err"; fail "mjcf --menagerie of 201 models: rc $rc, expected 1"; }
  grep -q "mj.yaml:1:1: the 201 cases have 201 distinct MuJoCo models: --menagerie would write 402 files (about " "$W/err" \
    || { cat "$W/err"; fail "no estimate in the refusal"; }
  grep -q "more than the limit of 200 models" "$W/err" || { cat "$W/err"; fail "no limit in the refusal"; }
  grep -q "pick one with --case NAME" "$W/err" || { cat "$W/err"; fail "no --case hint"; }
  [ ! -e "$W/men" ] || fail "the refused menagerie wrote $(ls "$W/men" | wc -l) files"
  [ ! -s "$W/out" ] || fail "the refused menagerie said: $(cat "$W/out")"
  echo "ok: mjcf --menagerie of 201 models refused before any file, with the estimate and the --case hint"
  ;;
merge-inside-shard)
  cat > "$W/n.yaml" <<YAML
name: n
robot: paper
trajectory: {dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.3, 0.5]}}
models: [analytic]
YAML
  for k in 1 2; do "$TAILSIM" run "$W/n.yaml" --shard $k/2 --out "$W/n$k" --quiet > /dev/null || fail "shard $k/2"; done
  for out in "$W/n1/sub" "$W/n2/a/b" "$W/n1/./sub/../sub2"; do
    rc=0
    "$TAILSIM" merge "$W/n1" "$W/n2" --out "$out" > /dev/null 2> "$W/err" || rc=$?
    [ $rc -eq 1 ] || { cat "$W/err"; fail "merge --out $out: rc $rc, expected 1"; }
    grep -q "is inside the shard .*: choose a folder outside the shards" "$W/err" || { cat "$W/err"; fail "merge --out $out: wrong message"; }
    grep -q -- "--fresh\|holds the results of a suite" "$W/err" && { cat "$W/err"; fail "merge --out $out: a suite in a staging folder"; }
  done
  [ -z "$(ls -d "$W"/n1/sub* "$W"/n2/a 2>/dev/null)" ] || fail "a refused merge left $(ls -d "$W"/n1/sub* "$W"/n2/a)"
  "$TAILSIM" merge "$W/n1" "$W/n2" --out "$W/merged" > /dev/null 2> "$W/err" || { cat "$W/err"; fail "merge outside the shards"; }
  echo "ok: merge --out inside a shard refused, naming the shard"
  ;;
*)
  fail "unknown class $CLASS"
  ;;
esac
