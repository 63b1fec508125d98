#!/usr/bin/env bash
# Result-folder persistence (docs/ARCHITECTURE.md "Result folder"), one class of hostile event per
# call, each registered as its own CTest test (tests/CMakeLists.txt):
#   hdf5-disk-full  an hdf5 sweep on a full disk reports the error and exits 1 (never a crash, no
#                   libhdf5 error stack) and keeps its finished cases; a no-op resume of a finished
#                   hdf5 folder on a nearly full disk copies nothing; merge onto a full disk and of a
#                   truncated .h5 give an error, never a crash. Needs root (a tmpfs is mounted).
#   hdf5-signals    an hdf5 sweep stopped by SIGTERM, SIGHUP, SIGINT and kill -9 resumes every case
#                   its journal had when the signal came; cases.jsonl holds one line per finished
#                   case after the resume. Prints the table "signal -> cases resumed".
#   folder-files    cases.jsonl, result.json and summary.json are opened only if they are regular
#                   files: a symlink is refused (nothing written through it), a FIFO never blocks, a
#                   huge file or /dev/zero is not read.
# Usage: result_folder_test.sh SOURCE_DIR BINARY_DIR CLASS
set -uo pipefail
SRC=$1 BIN=$2 CLASS=$3
TAILSIM=$BIN/tailsim
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_folder.XXXXXX")
ROOT=$W
MOUNTS=()
cleanup() {
  for m in "${MOUNTS[@]+"${MOUNTS[@]}"}"; do umount -l "$m" 2>/dev/null; done
  rm -rf "$ROOT"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }

# sweep.yaml: N cases (w_ss from 0.05 in steps of STEP), thin series in time_series.h5.
sweep() {  # sweep NAME STEP
  cat > "$W/$1.yaml" <<YAML
name: $1
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {range: [0.05, 0.95, $2]}}
models: [analytic]
output: {sample_dt_s: 0.0005, time_series: thin, time_series_file: hdf5}
YAML
}
small_disk() {  # small_disk DIR SIZE: a tmpfs of SIZE on DIR
  mkdir -p "$1"
  mount -t tmpfs -o "size=$2" tmpfs "$1" 2>/dev/null || { echo "SKIP: cannot mount a tmpfs (needs root)"; exit 0; }
  MOUNTS+=("$1")
}
# A run's exit code must be an exit, not a crash (>= 128 is a signal: 139 = SIGSEGV).
no_crash() {  # no_crash RC STDERR_FILE WHAT
  [ "$1" -lt 128 ] || { cat "$2"; fail "$3: killed by signal $(( $1 - 128 ))"; }
  if grep -q "HDF5-DIAG" "$2"; then head -5 "$2"; fail "$3: libhdf5's error stack reached stderr"; fi
}

case "$CLASS" in
hdf5-disk-full)
  sweep s 0.05  # 19 cases, ~10 KB of HDF5 each
  small_disk "$W/d1" 120k
  "$TAILSIM" run "$W/s.yaml" --out "$W/d1/o" --quiet --threads 1 > /dev/null 2> "$W/e1"
  rc=$?
  no_crash $rc "$W/e1" "hdf5 sweep on a full disk"
  [ $rc -eq 1 ] || fail "hdf5 sweep on a full disk exited $rc, want 1"
  grep -q "No space left on device" "$W/e1" || { cat "$W/e1"; fail "no disk-full message"; }
  kept=$(wc -l < "$W/d1/o/cases.jsonl")
  [ "$kept" -ge 1 ] || fail "no finished case kept on the full disk"
  # More room: the resume keeps every finished case and runs the rest.
  mount -o remount,size=4m "$W/d1" || fail "remount"
  out=$("$TAILSIM" run "$W/s.yaml" --out "$W/d1/o" --quiet --threads 1 2> "$W/e2")
  rc=$?
  no_crash $rc "$W/e2" "resume"
  [ $rc -eq 0 ] || { cat "$W/e2"; fail "resume exited $rc"; }
  echo "$out" | grep -q "$kept resumed" || fail "resume: want $kept resumed, got: $out"
  echo "disk full: $kept cases kept, all resumed"
  # A no-op resume of the finished folder with less free space than its .h5: nothing copied.
  ino=$(stat -c %i "$W/d1/o/time_series.h5")
  h5size=$(stat -c %s "$W/d1/o/time_series.h5")
  avail=$(df --output=avail -B1 "$W/d1" | tail -1)
  head -c $(( avail - h5size / 4 )) /dev/zero > "$W/d1/filler" 2>/dev/null
  out=$("$TAILSIM" run "$W/s.yaml" --out "$W/d1/o" --quiet --threads 1 2> "$W/e3")
  rc=$?
  no_crash $rc "$W/e3" "no-op resume on a full disk"
  [ $rc -eq 0 ] || { cat "$W/e3"; fail "no-op resume on a full disk exited $rc"; }
  [ "$(stat -c %i "$W/d1/o/time_series.h5")" = "$ino" ] || fail "no-op resume rewrote time_series.h5"
  echo "no-op resume on a full disk: time_series.h5 untouched"
  # merge of two hdf5 shards onto a full disk, and of a truncated .h5.
  for k in 1 2; do "$TAILSIM" run "$W/s.yaml" --out "$W/shard$k" --shard $k/2 --quiet > /dev/null || fail "shard $k"; done
  small_disk "$W/d2" 40k
  "$TAILSIM" merge "$W/shard1" "$W/shard2" --out "$W/d2/m" > /dev/null 2> "$W/e4"
  rc=$?
  no_crash $rc "$W/e4" "merge onto a full disk"
  [ $rc -eq 1 ] || { cat "$W/e4"; fail "merge onto a full disk exited $rc, want 1"; }
  grep -q "No space left on device" "$W/e4" || { cat "$W/e4"; fail "merge onto a full disk: no disk-full message"; }
  [ -z "$(ls -A "$W/d2")" ] || { ls -la "$W/d2"; fail "merge onto a full disk left files"; }
  cp -r "$W/shard2" "$W/shard2t"
  size=$(stat -c %s "$W/shard2t/time_series.h5")
  truncate -s $(( size / 2 )) "$W/shard2t/time_series.h5"
  "$TAILSIM" merge "$W/shard1" "$W/shard2t" --out "$W/m2" > /dev/null 2> "$W/e5"
  rc=$?
  no_crash $rc "$W/e5" "merge of a truncated .h5"
  [ $rc -eq 1 ] || { cat "$W/e5"; fail "merge of a truncated .h5 exited $rc, want 1"; }
  grep -q "time_series.h5" "$W/e5" || { cat "$W/e5"; fail "merge of a truncated .h5: the error does not name the file"; }
  echo "merge: full disk and truncated .h5 refused with a message"
  ;;
hdf5-signals)
  sweep big 0.001  # 901 cases
  # On a tmpfs where one can be mounted: each case's file is flushed to disk (fsync) before its
  # journal line, which costs ~5 ms a case on a disk and nothing here.
  if mkdir -p "$W/t" && mount -t tmpfs -o size=512m tmpfs "$W/t" 2>/dev/null; then
    MOUNTS+=("$W/t")
    mv "$W/big.yaml" "$W/t/"
    W=$W/t
  fi
  lines() { if [ -f "$1/cases.jsonl" ]; then wc -l < "$1/cases.jsonl"; else echo 0; fi; }
  start_and_stop() {  # start_and_stop DIR SIGNAL MIN_LINES: a run into DIR, stopped by SIGNAL once MIN_LINES are journaled
    "$TAILSIM" run "$W/big.yaml" --out "$1" --quiet --threads 2 > /dev/null 2> "$1.err" &
    local pid=$!
    for _ in $(seq 1 400); do  # at most 20 s
      kill -0 $pid 2>/dev/null || break
      [ "$(lines "$1")" -ge "$3" ] && break
      sleep 0.05
    done
    kill -s "$2" $pid
    wait $pid
  }
  printf '%-8s %-10s %-22s %s\n' signal "exit code" "cases in the journal" "cases resumed by the next run"
  for sig in TERM HUP INT KILL; do
    d="$W/o_$sig"
    start_and_stop "$d" $sig 100
    rc=$?
    if grep -q "HDF5-DIAG" "$d.err"; then fail "SIG$sig: libhdf5's error stack reached stderr"; fi
    journaled=$(lines "$d")
    [ "$journaled" -ge 100 ] || fail "SIG$sig: only $journaled cases journaled"
    out=$("$TAILSIM" run "$W/big.yaml" --out "$d" --quiet --threads 2 2>&1)
    resumed=$(echo "$out" | sed -n 's/.* \([0-9]*\) resumed.*/\1/p')
    printf '%-8s %-10s %-22s %s\n' "SIG$sig" "$rc" "$journaled" "$resumed"
    [ "${resumed:-0}" -ge "$journaled" ] || fail "SIG$sig: $journaled cases journaled, only ${resumed:-0} resumed"
    case $sig in TERM) want=143 ;; HUP) want=129 ;; INT) want=130 ;; KILL) want=137 ;; esac
    [ "$rc" -eq "$want" ] || { cat "$d.err"; fail "SIG$sig: exit code $rc, want $want"; }
  done
  # Repeated kill -9: the journal holds one line per finished case (compacted by each resume).
  d="$W/o_kills"
  for k in 1 2 3; do
    start_and_stop "$d" KILL $(( $(lines "$d") + 60 ))
    n=$(lines "$d")
    distinct=$(head -n "$n" "$d/cases.jsonl" | grep -o '"name":"[^"]*"' | sort -u | wc -l)
    echo "kill -9 $k: $n journal lines, $distinct cases"
    [ "$n" -eq "$distinct" ] || fail "cases.jsonl has $n lines for $distinct cases after $k kills"
  done
  ;;
folder-files)
  cat > "$W/n.yaml" <<YAML
name: n
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.3, 0.6]}}
models: [analytic]
output: {time_series: none}
YAML
  sed 's/time_series: none/time_series: full/' "$W/n.yaml" > "$W/f.yaml"
  refused() {  # refused WHAT FILE_NAMED: the run exits 1 within 10 s naming the file
    local rc=0
    timeout 10 "$TAILSIM" run "$3" --out "$W/$4" --quiet > /dev/null 2> "$W/err" || rc=$?
    [ $rc -ne 124 ] || fail "$1: the run blocked"
    [ $rc -eq 1 ] || { cat "$W/err"; fail "$1: exit $rc, want 1"; }
    grep -q "$2" "$W/err" || { cat "$W/err"; fail "$1: the error does not name $2"; }
    echo "$1: refused ($(head -c 150 "$W/err"))"
  }
  # cases.jsonl a symlink to a file outside --out: never written through.
  mkdir -p "$W/o1" && echo "precious" > "$W/outside.txt" && ln -s "$W/outside.txt" "$W/o1/cases.jsonl"
  refused "cases.jsonl -> a file outside --out" cases.jsonl "$W/n.yaml" o1
  [ "$(cat "$W/outside.txt")" = precious ] || fail "written through the cases.jsonl symlink"
  # a FIFO: never blocks; /dev/zero (through a symlink) and a 2 GiB file: never read.
  mkdir -p "$W/o2" && mkfifo "$W/o2/cases.jsonl"
  refused "cases.jsonl a FIFO" cases.jsonl "$W/n.yaml" o2
  mkdir -p "$W/o3" && ln -s /dev/zero "$W/o3/cases.jsonl"
  refused "cases.jsonl -> /dev/zero" cases.jsonl "$W/n.yaml" o3
  mkdir -p "$W/o4" && truncate -s 2G "$W/o4/cases.jsonl"
  refused "cases.jsonl of 2 GiB" cases.jsonl "$W/n.yaml" o4
  # summary.json a FIFO, a case's result.json a symlink out of the folder.
  mkdir -p "$W/o5" && mkfifo "$W/o5/summary.json"
  refused "summary.json a FIFO" summary.json "$W/f.yaml" o5
  "$TAILSIM" run "$W/f.yaml" --out "$W/o6" --quiet > /dev/null || fail "run f"
  cp "$W/o6/cases/w_ss=0.3/result.json" "$W/outside.json"
  rm "$W/o6/cases/w_ss=0.3/result.json" && ln -s "$W/outside.json" "$W/o6/cases/w_ss=0.3/result.json"
  refused "result.json -> a file outside --out" result.json "$W/f.yaml" o6
  ;;
*) echo "unknown CLASS $CLASS"; exit 2 ;;
esac
echo PASS
