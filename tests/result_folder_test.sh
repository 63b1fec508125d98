#!/usr/bin/env bash
# Result-folder persistence (docs/ARCHITECTURE.md "Result folder"), one class of hostile event per
# call, each registered as its own CTest test (tests/CMakeLists.txt):
#   hdf5-disk-full  an hdf5 sweep on a full disk reports the error and exits 1 (never a crash, no
#                   libhdf5 error stack) and keeps its finished cases; a no-op resume of a finished
#                   hdf5 folder on a nearly full disk copies nothing; merge onto a full disk and of a
#                   truncated .h5 give an error, never a crash; the final join needs only the room
#                   of its copy; plot on a full disk names the condition and leaves no partial figure.
#                   Needs root (a tmpfs is mounted).
#   hdf5-signals    an hdf5 sweep stopped by SIGTERM, SIGHUP, SIGINT and kill -9 resumes every case
#                   its journal had when the signal came; cases.jsonl holds one line per finished
#                   case after the resume. Prints the table "signal -> cases resumed".
#   user-files      tailsim replaces or deletes only files it wrote: run --out D refuses D's own
#                   experiment.yaml, results.csv, summary.json; --fresh keeps the user's files under
#                   cases/, plots/, renders/; optimize and maneuver refuse a run folder and take its
#                   lock; mjcf --menagerie refuses to overwrite a hand-edited model file.
#   hdf5-damaged    random bytes in a finished folder's or a shard's time_series.h5: resume runs
#                   the cases again (never a crash, never a stuck folder); merge refuses the shard.
#   folder-files    cases.jsonl, result.json and summary.json are opened (by run and plot) only if
#                   they are regular files: a symlink is refused (nothing written through it), a FIFO never blocks, a
#                   huge file or /dev/zero is not read; a hard-linked .tailsim.lock or cases.jsonl is
#                   refused, the linked file never truncated.
#   merge-signals   merge stopped by SIGTERM, SIGHUP or SIGINT exits 128+signal with a message and
#                   leaves no staging folder; after a kill -9 the next merge removes the dead merge's
#                   staging folder, and never a user's folder named like one.
#   out-of-memory   a legal run out of memory is reported naming the case and what to change.
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
  # The final join reserves what the copy can need (the parts' size and a little), not 1.5 x: a
  # 91-case sweep (parts 4.5 MB, time_series.h5 3.8 MB) joins on a 10.5 MB disk (5.6 MB free at the
  # join; 1.5 x parts would be 6.8 MB).
  sweep j 0.01
  small_disk "$W/d3" 10500k
  "$TAILSIM" run "$W/j.yaml" --out "$W/d3/o" --quiet --threads 2 > /dev/null 2> "$W/e6"
  rc=$?
  no_crash $rc "$W/e6" "join on a disk with room for it"
  [ $rc -eq 0 ] || { cat "$W/e6"; fail "join on a disk with room for it (parts $(du -sb "$W/d3/o/time_series.h5.d" 2>/dev/null | cut -f1) B, $(df --output=avail -B1 "$W/d3" | tail -1) B free) exited $rc"; }
  [ -f "$W/d3/o/time_series.h5" ] && [ ! -e "$W/d3/o/time_series.h5.d" ] || fail "join: no time_series.h5, or parts left"
  echo "join: $(stat -c %s "$W/d3/o/time_series.h5") B joined on a 10.5 MB disk"
  # plot on a full disk: a clean error naming the disk-full condition, no empty or partial figure left.
  cat > "$W/c12.yaml" <<YAML
name: c
robot: paper
tail: {links: 1}
trajectory: {theta0_deg: 45, dtheta_deg: {sweep: [-90, -45, 45, 90]}, dT_s: 0.25, w_ss: {sweep: [0.3, 0.5, 0.7]}}
models: [analytic]
output: {sample_dt_s: 0.0005, time_series: thin, time_series_file: csv}
YAML
  small_disk "$W/d4" 2m
  "$TAILSIM" run "$W/c12.yaml" --out "$W/d4/p" --quiet > /dev/null || fail "csv sweep for plot"
  head -c $(( $(df --output=avail -B1 "$W/d4" | tail -1) - 150000 )) /dev/zero > "$W/d4/fill" 2>/dev/null
  rc=0; "$TAILSIM" plot "$W/d4/p" > /dev/null 2> "$W/e6" || rc=$?
  no_crash $rc "$W/e6" "plot on a full disk"
  [ $rc -eq 1 ] || { cat "$W/e6"; fail "plot on a full disk exited $rc, want 1"; }
  grep -q "No space left on device" "$W/e6" || { cat "$W/e6"; fail "plot on a full disk: no disk-full message"; }
  bad=$(find "$W/d4/p/plots" -type f \( -size 0 -o -name '*.tmp.*' \) 2>/dev/null)
  [ -z "$bad" ] || { ls -la "$W/d4/p/plots"; fail "plot on a full disk left empty or temporary files: $bad"; }
  for f in "$W"/d4/p/plots/*.svg; do [ -e "$f" ] || continue; tail -c 20 "$f" | grep -q "</svg>" || fail "partial figure $f kept"; done
  echo "plot on a full disk: $(head -c 150 "$W/e6")"
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
    # SIGTERM and SIGHUP stop the run as Ctrl-C does: the running cases finish, the count is printed.
    [ "$sig" = KILL ] || grep -q "cases saved in" "$d.err" || { cat "$d.err"; fail "SIG$sig: not a clean stop"; }
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
user-files)
  sweep s 0.3  # 4 cases
  sed 's/time_series: thin, time_series_file: hdf5/time_series: full/' "$W/s.yaml" > "$W/f.yaml"
  refused() {  # refused WHAT FILE_NAMED CMD...: exit 1 naming the file
    local what=$1 named=$2 rc=0
    shift 2
    "$@" > /dev/null 2> "$W/err" || rc=$?
    [ $rc -eq 1 ] || { cat "$W/err"; fail "$what: exit $rc, want 1"; }
    grep -q "$named" "$W/err" || { cat "$W/err"; fail "$what: the error does not name $named"; }
    echo "$what: refused ($(head -c 160 "$W/err"))"
  }
  # run --out D where D holds the user's own files: each refused, unchanged.
  for own in experiment.yaml results.csv summary.json; do
    d="$W/own_$own"
    mkdir -p "$d" && cp "$W/f.yaml" "$d/input.yaml"
    echo '{"mine": true}' > "$d/$own"
    [ "$own" = experiment.yaml ] && cp "$W/f.yaml" "$d/experiment.yaml"  # run from D's own experiment.yaml
    refused "run --out D with the user's $own" "$own was not written by tailsim" "$TAILSIM" run "$d/input.yaml" --out "$d" --quiet
    [ "$own" = experiment.yaml ] && ! cmp -s "$W/f.yaml" "$d/experiment.yaml" && fail "$own replaced"
    [ "$own" = experiment.yaml ] || grep -q mine "$d/$own" || fail "$own replaced"
  done
  # --fresh deletes only what tailsim wrote.
  d="$W/fresh"
  "$TAILSIM" run "$W/f.yaml" --out "$d" --quiet > /dev/null || fail "run"
  mkdir -p "$d/plots" "$d/renders" && echo n > "$d/cases/w_ss=0.35/notes.txt" && echo p > "$d/plots/mine.png"
  echo r > "$d/renders/mine.png" && mkdir -p "$d/cases/mine" && echo m > "$d/cases/mine/data.csv"
  "$TAILSIM" run "$W/f.yaml" --out "$d" --quiet --fresh > /dev/null 2> "$W/err" || { cat "$W/err"; fail "--fresh"; }
  for f in "cases/w_ss=0.35/notes.txt" plots/mine.png renders/mine.png cases/mine/data.csv; do
    [ -f "$d/$f" ] || fail "--fresh deleted the user's $f"
  done
  grep -q "kept .*notes.txt" "$W/err" || { cat "$W/err"; fail "--fresh does not say what it kept"; }
  [ -f "$d/cases/w_ss=0.35/result.json" ] && [ -f "$d/summary.json" ] || fail "--fresh run incomplete"
  echo "--fresh: the user's files under cases/, plots/, renders/ kept"
  # optimize / maneuver: a run folder's summary.json is not theirs; the folder lock is taken.
  refused "optimize into a run folder" "holds the results of" "$TAILSIM" optimize "$SRC/configs/design/spline_n1.yaml" --out "$d" --quiet
  refused "maneuver into a run folder" "holds the results of" "$TAILSIM" maneuver "$SRC/configs/design/maneuver_90.yaml" --out "$d" --quiet
  mkdir -p "$W/opt" && flock "$W/opt/.tailsim.lock" sleep 20 &
  lockpid=$!
  sleep 0.5
  refused "optimize into a folder in use" "in use" "$TAILSIM" optimize "$SRC/configs/design/spline_n1.yaml" --out "$W/opt" --quiet
  kill $lockpid 2>/dev/null; wait $lockpid 2>/dev/null
  # mjcf --menagerie: a hand-edited model file is never overwritten; tailsim's own ones are.
  "$TAILSIM" mjcf --links 2 --menagerie "$W/men" > /dev/null || fail "mjcf --menagerie"
  "$TAILSIM" mjcf --links 2 --menagerie "$W/men" > /dev/null || fail "mjcf --menagerie over its own files"
  f=$(ls "$W/men"/tailsim_*.xml | head -1)
  sed -i 's/<mujoco /<mujoco  /' "$f" && cp "$f" "$W/edited.xml"
  refused "mjcf --menagerie over a hand-edited file" "$(basename "$f")" "$TAILSIM" mjcf --links 2 --menagerie "$W/men"
  cmp -s "$f" "$W/edited.xml" || fail "the hand-edited model file was replaced"
  # optimize, maneuver, report and the figures: the user's files refused before any work, unchanged.
  own_file() {  # own_file WHAT FILE CMD...: DIR/FILE holds "mine"; the command refuses it, FILE unchanged
    local what=$1 file=$2 dir=$W/own_${RANDOM}
    shift 2
    mkdir -p "$(dirname "$dir/$file")" && echo mine > "$dir/$file"
    refused "$what with the user's $file" "$file was not written by tailsim" "${@//@DIR@/$dir}"
    [ "$(cat "$dir/$file")" = mine ] || fail "$what replaced the user's $file"
  }
  for f in summary.json history.csv best.yaml plots/history.png plots/history.gp; do
    own_file optimize "$f" "$TAILSIM" optimize "$SRC/configs/design/spline_n1.yaml" --out @DIR@ --quiet
  done
  for f in summary.json strokes.csv plots/heading.gp; do
    own_file maneuver "$f" "$TAILSIM" maneuver "$SRC/configs/design/maneuver_90.yaml" --out @DIR@ --quiet
  done
  d="$W/plotted"
  "$TAILSIM" run "$W/f.yaml" --out "$d" --quiet --plot > /dev/null 2> "$W/err" || { cat "$W/err"; fail "run --plot"; }
  "$TAILSIM" run "$W/f.yaml" --out "$d" --quiet --plot > /dev/null 2> "$W/err" || { cat "$W/err"; fail "run --plot over its own figures"; }
  "$TAILSIM" report "$d" > /dev/null 2> "$W/err" || { cat "$W/err"; fail "report"; }
  "$TAILSIM" report "$d" > /dev/null 2> "$W/err" || { cat "$W/err"; fail "report over its own report.md"; }
  for f in report.md figures.html index.html "plots/$(cd "$d/plots" && ls *.png | head -1)" page/data.js; do
    cmd=plot
    [ "$f" = report.md ] && cmd=report
    cp -r "$d" "$W/p2" && echo mine > "$W/p2/$f"
    refused "$cmd with the user's $f" "$f.*not written by tailsim" "$TAILSIM" $cmd "$W/p2"
    [ "$(cat "$W/p2/$f")" = mine ] || fail "$cmd replaced the user's $f"
    rm -rf "$W/p2"
  done
  # --fresh deletes tailsim's own figures and pages, keeps the user's.
  echo mine > "$d/plots/mine.png"
  "$TAILSIM" run "$W/f.yaml" --out "$d" --quiet --fresh > /dev/null 2> "$W/err" || { cat "$W/err"; fail "--fresh of a plotted folder"; }
  left=$(cd "$d" && ls plots page report.md figures.html index.html 2>/dev/null | grep -v -e '^mine.png$' -e '^plots:$' -e '^$' || true)
  [ -z "$left" ] || fail "--fresh left tailsim's own figures or pages: $left"
  [ -f "$d/plots/mine.png" ] || fail "--fresh deleted the user's plots/mine.png"
  echo "optimize, maneuver, plot, report: the user's files refused; --fresh deletes tailsim's figures only"
  # The hdf5 join deletes its own part files only: a user's file in time_series.h5.d stays, with a note.
  sweep hj 0.3
  mkdir -p "$W/hj/time_series.h5.d" && echo mine > "$W/hj/time_series.h5.d/mine.txt"
  "$TAILSIM" run "$W/hj.yaml" --out "$W/hj" --quiet > /dev/null 2> "$W/err" || { cat "$W/err"; fail "hdf5 run beside a user's file"; }
  [ "$(cat "$W/hj/time_series.h5.d/mine.txt" 2>/dev/null)" = mine ] || fail "the hdf5 join deleted the user's time_series.h5.d/mine.txt"
  grep -q "mine.txt" "$W/err" || { cat "$W/err"; fail "the hdf5 join kept mine.txt without a note"; }
  left=$(ls "$W/hj/time_series.h5.d" | grep -v '^mine.txt$' || true)
  [ -z "$left" ] || fail "the hdf5 join left its own parts: $left"
  sweep hk 0.3
  "$TAILSIM" run "$W/hk.yaml" --out "$W/hk" --quiet > /dev/null || fail "hdf5 run"
  [ ! -e "$W/hk/time_series.h5.d" ] || fail "the hdf5 join left time_series.h5.d with only its own files in it"
  echo "hdf5 join: its own parts deleted, the user's time_series.h5.d/mine.txt kept with a note"
  ;;
hdf5-damaged)
  # Random bytes (seeded) written into a finished folder's time_series.h5: the resume never crashes
  # and never stays stuck (rc 0, then a resume runs nothing); the same in a shard: merge refuses it
  # naming the file and the shard.
  sweep s 0.1  # 10 cases
  flip() {  # flip FILE SEED COUNT: COUNT random bytes at random offsets
    python3 - "$@" <<'PY'
import random, sys
p, seed, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
r = random.Random(seed); b = bytearray(open(p, 'rb').read())
for _ in range(count): b[r.randrange(len(b))] = r.randrange(256)
open(p, 'wb').write(b)
PY
  }
  "$TAILSIM" run "$W/s.yaml" --out "$W/clean" --quiet > /dev/null || fail "clean run"
  for seed in $(seq 1 12); do
    rm -rf "$W/z" && cp -r "$W/clean" "$W/z" && flip "$W/z/time_series.h5" "$seed" 40
    rc=0
    timeout 60 "$TAILSIM" run "$W/s.yaml" --out "$W/z" --quiet > /dev/null 2> "$W/e" || rc=$?
    no_crash $rc "$W/e" "resume of a damaged time_series.h5 (seed $seed)"
    [ $rc -eq 0 ] || { cat "$W/e"; fail "resume of a damaged time_series.h5 (seed $seed) exited $rc"; }
    out=$("$TAILSIM" run "$W/s.yaml" --out "$W/z" --quiet 2> "$W/e") || { cat "$W/e"; fail "second resume (seed $seed)"; }
    echo "$out" | grep -q " 0 run" || fail "seed $seed: the second resume ran cases again: $out"
  done
  echo "damaged time_series.h5, 12 seeds: resumed, cases run again, no crash"
  "$TAILSIM" run "$W/s.yaml" --out "$W/sh1" --shard 1/2 --quiet > /dev/null || fail "shard 1"
  "$TAILSIM" run "$W/s.yaml" --out "$W/sh2" --shard 2/2 --quiet > /dev/null || fail "shard 2"
  for seed in $(seq 1 6); do
    rm -rf "$W/shx" "$W/m" && cp -r "$W/sh1" "$W/shx" && flip "$W/shx/time_series.h5" "$seed" 20
    rc=0
    timeout 60 "$TAILSIM" merge "$W/shx" "$W/sh2" --out "$W/m" > /dev/null 2> "$W/e" || rc=$?
    no_crash $rc "$W/e" "merge of a damaged shard (seed $seed)"
    [ $rc -eq 1 ] || { cat "$W/e"; fail "merge of a damaged shard (seed $seed) exited $rc, want 1"; }
    grep -q "shx/time_series.h5" "$W/e" || { cat "$W/e"; fail "merge of a damaged shard: the error does not name the file"; }
    [ -z "$(ls -d "$W"/m.merge.tmp.* 2>/dev/null)" ] || fail "merge left its staging folder"
  done
  "$TAILSIM" merge "$W/sh1" "$W/sh2" --out "$W/m" > /dev/null 2> "$W/e" || { cat "$W/e"; fail "merge of intact shards"; }
  echo "damaged shard, 6 seeds: merge refused naming it; intact shards merge"
  # Damaged parts after a kill -9 (time_series.h5.d/<case>.h5): those cases run again, no crash.
  sweep k 0.01  # 91 cases
  "$TAILSIM" run "$W/k.yaml" --out "$W/pk" --quiet --threads 1 > /dev/null 2>&1 &
  pid=$!
  for _ in $(seq 1 200); do
    [ "$(cat "$W/pk/cases.jsonl" 2> /dev/null | wc -l)" -ge 20 ] && break
    sleep 0.02
  done
  kill -9 $pid 2> /dev/null; wait $pid 2> /dev/null
  parts=$(ls "$W/pk/time_series.h5.d"/*.h5 2> /dev/null | head -8)
  [ -n "$parts" ] || { echo "note: the sweep finished before kill -9: no parts to damage"; exit 0; }
  seed=0
  for p in $parts; do seed=$((seed + 1)); flip "$p" "$seed" 200; done
  rc=0
  timeout 60 "$TAILSIM" run "$W/k.yaml" --out "$W/pk" --quiet > /dev/null 2> "$W/e" || rc=$?
  no_crash $rc "$W/e" "resume with damaged parts"
  [ $rc -eq 0 ] || { cat "$W/e"; fail "resume with damaged parts exited $rc"; }
  out=$("$TAILSIM" run "$W/k.yaml" --out "$W/pk" --quiet 2> "$W/e") || { cat "$W/e"; fail "second resume after damaged parts"; }
  echo "$out" | grep -q " 0 run" || fail "damaged parts: the second resume ran cases again: $out"
  "$TAILSIM" run "$W/k.yaml" --out "$W/kc" --quiet > /dev/null || fail "clean run of k"
  python3 "$SRC/scripts/compare_folders.py" "$W/kc" "$W/pk" > "$W/cmp" 2>&1 || { cat "$W/cmp"; fail "damaged parts: the folder differs from a clean run (a damaged series published)"; }
  echo "$(echo "$parts" | wc -w) damaged parts after kill -9: their cases ran again, no crash"
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
  # A hard link to a file outside --out as .tailsim.lock or as a cases.jsonl with a torn last line:
  # refused naming it, the linked file unchanged (never truncated).
  mkdir -p "$W/hl1" && echo "precious data" > "$W/precious1.txt" && ln "$W/precious1.txt" "$W/hl1/.tailsim.lock"
  refused "hard-linked .tailsim.lock" "tailsim.lock.*hard link" "$W/n.yaml" hl1
  [ "$(cat "$W/precious1.txt")" = "precious data" ] || fail "the hard-linked .tailsim.lock's file was changed"
  mkdir -p "$W/hl2" && "$TAILSIM" run "$W/n.yaml" --out "$W/hl2" --quiet > /dev/null || fail "run into hl2"
  printf '%s\nprecious tail without newline' "$(head -1 "$W/hl2/cases.jsonl")" > "$W/precious2.txt"
  cp "$W/precious2.txt" "$W/precious2.orig" && rm "$W/hl2/cases.jsonl" && ln "$W/precious2.txt" "$W/hl2/cases.jsonl"
  refused "hard-linked cases.jsonl" "cases.jsonl.*hard link" "$W/n.yaml" hl2
  cmp -s "$W/precious2.txt" "$W/precious2.orig" || fail "the hard-linked cases.jsonl's file was changed"
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
  rc=0
  timeout 10 "$TAILSIM" plot "$W/o5" > /dev/null 2> "$W/err" || rc=$?
  [ $rc -eq 1 ] && grep -q summary.json "$W/err" || { cat "$W/err"; fail "plot of a folder whose summary.json is a FIFO: exit $rc"; }
  echo "plot with summary.json a FIFO: refused ($(head -c 120 "$W/err"))"
  "$TAILSIM" run "$W/f.yaml" --out "$W/o6" --quiet > /dev/null || fail "run f"
  cp "$W/o6/cases/w_ss=0.3/result.json" "$W/outside.json"
  rm "$W/o6/cases/w_ss=0.3/result.json" && ln -s "$W/outside.json" "$W/o6/cases/w_ss=0.3/result.json"
  refused "result.json -> a file outside --out" result.json "$W/f.yaml" o6
  # cases.jsonl read line by line: 900 MB without a newline is refused at once (never read whole,
  # never cut to 0); a first line that is not a tailsim entry: not tailsim's file, left unchanged.
  mkdir -p "$W/o7" && truncate -s 900M "$W/o7/cases.jsonl"
  # Under AddressSanitizer (scripts/sanitize.sh sets ASAN_OPTIONS) a virtual-memory limit cannot hold
  # its shadow memory: the check runs without the limit there.
  if [ -n "${ASAN_OPTIONS:-}" ]; then
    refused "cases.jsonl of 900 MB without a newline" cases.jsonl "$W/n.yaml" o7 || exit 1
  else
    ( ulimit -v 1200000; refused "cases.jsonl of 900 MB without a newline (1.2 GB of memory)" cases.jsonl "$W/n.yaml" o7 ) || exit 1
  fi
  [ "$(stat -c %s "$W/o7/cases.jsonl")" = 943718400 ] || fail "cases.jsonl of 900 MB was changed"
  grep -q "bad_alloc" "$W/err" && fail "std::bad_alloc reached the user"
  mkdir -p "$W/o8" && printf 'my notes\n{"not": "tailsim"}\n' > "$W/o8/cases.jsonl" && cp "$W/o8/cases.jsonl" "$W/notes"
  refused "cases.jsonl whose first line is not a tailsim entry" cases.jsonl "$W/n.yaml" o8
  cmp -s "$W/o8/cases.jsonl" "$W/notes" || fail "the user's cases.jsonl was changed"
  mkdir -p "$W/o9" && printf 'my notes, no newline' > "$W/o9/cases.jsonl"
  refused "cases.jsonl of one line that is not a tailsim entry, no newline" cases.jsonl "$W/n.yaml" o9
  [ "$(cat "$W/o9/cases.jsonl")" = "my notes, no newline" ] || fail "the user's cases.jsonl was cut"
  # A folder of --out that is a symlink to a folder outside it is never written through: cases/,
  # time_series.h5.d/, one case's folder, plots/ (run --plot).
  sed 's/{time_series: none}/{time_series: thin, time_series_file: hdf5}/' "$W/n.yaml" > "$W/h.yaml"
  link_refused() {  # link_refused WHAT LINK YAML ARGS...: DIR/LINK -> outside: exit 1 naming it, nothing outside
    local what=$1 link=$2 yaml=$3 rc=0
    shift 3
    rm -rf "$W/ol" "$W/outside_dir" && mkdir -p "$W/outside_dir" "$(dirname "$W/ol/$link")"
    ln -s "$W/outside_dir" "$W/ol/$link"
    timeout 20 "$TAILSIM" run "$yaml" --out "$W/ol" --quiet "$@" > /dev/null 2> "$W/err" || rc=$?
    [ $rc -eq 1 ] || { cat "$W/err"; fail "$what: exit $rc, want 1"; }
    grep -q "$link" "$W/err" || { cat "$W/err"; fail "$what: the error does not name $link"; }
    [ -z "$(ls -A "$W/outside_dir")" ] || fail "$what: written through the link: $(ls "$W/outside_dir")"
    echo "$what: refused ($(head -c 150 "$W/err"))"
  }
  link_refused "cases -> a folder outside --out" cases "$W/f.yaml"
  link_refused "time_series.h5.d -> a folder outside --out" time_series.h5.d "$W/h.yaml"
  link_refused "cases/w_ss=0.6 -> a folder outside --out" "cases/w_ss=0.6" "$W/f.yaml"
  link_refused "plots -> a folder outside --out (run --plot)" plots "$W/f.yaml" --plot
  ;;
merge-signals)
  sweep s 0.005  # 181 cases
  for k in 1 2; do "$TAILSIM" run "$W/s.yaml" --out "$W/shard$k" --shard $k/2 --quiet > /dev/null || fail "shard $k"; done
  start_merge() {  # start_merge OUT: a merge into OUT, returns once its staging folder exists (pid in $mpid)
    "$TAILSIM" merge "$W/shard1" "$W/shard2" --out "$1" --threads 1 > /dev/null 2> "$1.err" &
    mpid=$!
    for _ in $(seq 1 2000); do
      [ -d "$1.merge.tmp.$mpid" ] && return 0
      kill -0 $mpid 2>/dev/null || break
      sleep 0.005
    done
    fail "merge into $1: no staging folder seen"
  }
  for sig in TERM HUP INT; do
    start_merge "$W/m_$sig"
    kill -s $sig $mpid
    rc=0; wait $mpid || rc=$?
    want=$(( 128 + $(kill -l $sig) ))
    [ $rc -eq $want ] || { cat "$W/m_$sig.err"; fail "merge stopped by SIG$sig exited $rc, want $want"; }
    grep -q "interrupted" "$W/m_$sig.err" || { cat "$W/m_$sig.err"; fail "merge stopped by SIG$sig: no message"; }
    left=$(ls -d "$W"/m_$sig.merge.tmp.* 2>/dev/null)
    [ -z "$left" ] || fail "merge stopped by SIG$sig left its staging folder $left"
    [ ! -e "$W/m_$sig" ] || [ -z "$(ls -A "$W/m_$sig")" ] || fail "merge stopped by SIG$sig wrote $W/m_$sig"
    echo "merge stopped by SIG$sig: exit $rc, $(head -c 100 "$W/m_$sig.err")"
  done
  # kill -9: the staging folder stays; the next merge removes it (its pid is dead, its manifest marks
  # it as tailsim's) and keeps a user's folder named like one.
  start_merge "$W/mk"
  kill -9 $mpid; wait $mpid 2>/dev/null
  stale="$W/mk.merge.tmp.$mpid"
  [ -d "$stale" ] || fail "kill -9: no staging folder to clean (the test needs one)"
  mkdir -p "$W/mk.merge.tmp.999999" && echo mine > "$W/mk.merge.tmp.999999/mine.txt"
  # killed between creating its staging folder and marking it: an empty folder (or one holding only
  # the manifest's first bytes) of a dead pid is removed too; the kill above may land in that window.
  mkdir -p "$W/mk.merge.tmp.999998" "$W/mk.merge.tmp.999997" && : > "$W/mk.merge.tmp.999997/.tailsim-manifest"
  "$TAILSIM" merge "$W/shard1" "$W/shard2" --out "$W/mk" > /dev/null 2> "$W/mk.err2" || { cat "$W/mk.err2"; fail "merge after kill -9"; }
  [ ! -e "$stale" ] || { ls -la "$stale"; fail "the dead merge's staging folder $stale was not removed"; }
  [ ! -e "$W/mk.merge.tmp.999998" ] || fail "an empty staging folder of a dead merge was not removed"
  [ ! -e "$W/mk.merge.tmp.999997" ] || fail "a dead merge's staging folder holding only an empty manifest was not removed"
  [ "$(cat "$W/mk.merge.tmp.999999/mine.txt" 2>/dev/null)" = mine ] || fail "a user's folder named like a staging folder was deleted"
  echo "kill -9: the next merge removed the dead merge's staging folder, kept the user's"
  ;;
out-of-memory)
  # Under AddressSanitizer (scripts/sanitize.sh sets ASAN_OPTIONS) an address-space limit cannot hold
  # ASan's shadow memory: this class runs in the Release stage only.
  if [ -n "${ASAN_OPTIONS:-}" ]; then echo "out-of-memory: skipped under AddressSanitizer (ulimit -v)"; exit 0; fi
  # A legal run (8e5 rows per run) of 2 threads under a 1.2 GB address-space limit: tailsim's own
  # words naming the case and what to change, never a raw "std::bad_alloc".
  cat > "$W/big.yaml" <<YAML
name: big
robot: paper
tail: {links: 6}
trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {sweep: [0.3, 0.5]}}
models: [analytic]
output: {sample_dt_s: 0.000005, duration_s: 4, time_series: full, time_series_file: csv}
YAML
  rc=0
  (ulimit -v 1200000; exec timeout 120 "$TAILSIM" run "$W/big.yaml" --out "$W/big" --threads 2 --quiet) > /dev/null 2> "$W/err" || rc=$?
  no_crash $rc "$W/err" "run out of memory"
  if [ $rc -eq 0 ]; then echo "SKIP: the run fit in 1.2 GB here"; exit 0; fi
  grep -q "bad_alloc" "$W/err" && { cat "$W/err"; fail "out of memory reported as raw std::bad_alloc"; }
  grep -q "out of memory while running" "$W/err" || { cat "$W/err"; fail "out of memory: no message in tailsim's words"; }
  # with the memory a running case holds (6 links: 39 columns x 8e5 rows x 8 B = 250 MB)
  grep -q "at least about 250 MB for this one" "$W/err" || { cat "$W/err"; fail "out of memory: no MB figure"; }
  echo "out of memory: $(head -c 150 "$W/err")"
  ;;
hdf5-damaged-manifest)
  # A damaged .h5 whose manifest line matches it (a shard copied from another machine carries a
  # manifest that names whatever it holds): libhdf5 crashed inside H5Ocopy (SIGSEGV; seeds 2, 11, 17
  # of 24 for merge, 11 and 15 for a resume). Now the copy runs in a child process: a crash there is
  # an error naming the file, rc 1, and tailsim itself never dies.
  sweep s 0.1  # 10 cases
  damage() {  # damage DIR SEED: 10 random bytes into DIR/time_series.h5, then DIR's manifest names it as it is
    python3 - "$@" <<'PY'
import hashlib, os, random, sys
d, seed = sys.argv[1], int(sys.argv[2])
p = os.path.join(d, 'time_series.h5'); r = random.Random(seed); b = bytearray(open(p, 'rb').read())
for _ in range(10): b[r.randrange(len(b))] = r.randrange(256)
open(p, 'wb').write(b)
m = os.path.join(d, '.tailsim-manifest'); out = []
for line in open(m):
    h, n = line.rstrip('\n').split('  ', 1)
    f = os.path.join(d, n)
    if os.path.isfile(f): h = hashlib.sha256(open(f, 'rb').read()).hexdigest()
    out.append(h + '  ' + n + '\n')
open(m, 'w').write(''.join(out))
PY
  }
  "$TAILSIM" run "$W/s.yaml" --out "$W/sh1" --shard 1/2 --quiet > /dev/null || fail "shard 1"
  "$TAILSIM" run "$W/s.yaml" --out "$W/sh2" --shard 2/2 --quiet > /dev/null || fail "shard 2"
  "$TAILSIM" run "$W/s.yaml" --out "$W/clean" --quiet > /dev/null || fail "clean run"
  refused=0
  for seed in $(seq 1 24); do
    rm -rf "$W/shx" "$W/m" && cp -r "$W/sh1" "$W/shx" && damage "$W/shx" "$seed"
    rc=0
    timeout 60 "$TAILSIM" merge "$W/shx" "$W/sh2" --out "$W/m" > /dev/null 2> "$W/e" || rc=$?
    no_crash $rc "$W/e" "merge of a damaged shard with a matching manifest (seed $seed)"
    [ -z "$(ls -d "$W"/m.merge.tmp.* 2>/dev/null)" ] || fail "merge (seed $seed) left its staging folder"
    if grep -q "libhdf5 crashed" "$W/e"; then
      refused=$((refused + 1))
      grep -q "shx/time_series.h5 (shard .*shx) is damaged" "$W/e" || { cat "$W/e"; fail "seed $seed: the error does not name the file and shard"; }
    fi
    rm -rf "$W/z" && cp -r "$W/clean" "$W/z" && damage "$W/z" "$seed" && sed -i 2d "$W/z/cases.jsonl"
    rc=0
    timeout 60 "$TAILSIM" run "$W/s.yaml" --out "$W/z" --quiet > /dev/null 2> "$W/e" || rc=$?
    no_crash $rc "$W/e" "resume of a damaged time_series.h5 with a matching manifest (seed $seed)"
    if grep -q "libhdf5 crashed" "$W/e"; then
      refused=$((refused + 1))
      grep -q "z/time_series.h5 or a part in .*is damaged" "$W/e" || { cat "$W/e"; fail "seed $seed: the resume's error does not name the file"; }
    fi
  done
  echo "damaged .h5 with a matching manifest, 24 seeds, merge and resume: no crash ($refused libhdf5 crashes reported as errors)"
  ;;
*) echo "unknown CLASS $CLASS"; exit 2 ;;
esac
echo PASS
