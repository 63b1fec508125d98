#!/usr/bin/env bash
# The command line as a user meets it: --version (and in summary.json), usage errors naming the
# unknown word (exit 2), render/run --case checked (exit 1), failed model runs (exit 3), outputs the
# user names written through symlinks/devices/stdout, the progress output in a log, Ctrl-C (130).
#   tests/cli_test.sh SOURCE_DIR BUILD_DIR      (CTest: cli)
set -euo pipefail
src=$(cd "$1" && pwd)
bld=$(cd "$2" && pwd)
tailsim="$bld/tailsim"
[ -x "$tailsim" ] || { echo "FAIL: $tailsim not built"; exit 1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_cli.XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work"

fail() { printf 'FAIL: %b\n' "$*"; exit 1; }
ok() { echo "  ok: $*"; }
# run EXPECTED_RC CMD...: stdout -> out.txt, stderr -> err.txt; fails unless the exit code matches.
run() {
  local want=$1; shift
  local rc=0
  "$@" >out.txt 2>err.txt || rc=$?
  [ "$rc" -eq "$want" ] || fail "exit $rc (want $want) from: $*\nstdout: $(head -c 2000 out.txt)\nstderr: $(head -c 2000 err.txt)"
}
robot="$src/configs/robots/paper_quadruped.yaml"

echo "== version"
version=$(sed -n 's/^project(tailsim VERSION \([0-9.]*\).*/\1/p' "$src/CMakeLists.txt")
[ -n "$version" ] || fail "no project(tailsim VERSION ...) in CMakeLists.txt"
run 0 "$tailsim" --version
grep -q "^tailsim $version\b" out.txt || fail "--version printed '$(cat out.txt)', not tailsim $version"
ok "--version: $(cat out.txt)"

echo "== usage errors: exit 2, the unknown word named"
run 2 "$tailsim" rn configs/default.yaml
grep -q "unknown subcommand 'rn'" err.txt || fail "tailsim rn: $(cat err.txt)"
grep -q "run, " err.txt || fail "tailsim rn does not list the subcommands: $(cat err.txt)"
run 2 "$tailsim" run "$src/configs/default.yaml" --out r --bogus
grep -q -- "--bogus" err.txt || fail "an unknown flag is not named: $(cat err.txt)"
# ... also when a required argument is missing too (CLI11 alone says "--out is required").
for args in "run --bogus" "run $src/configs/default.yaml --bogus" "mjcf --bogus" "--bogus"; do
  run 2 "$tailsim" $args
  grep -q -- "unknown option '--bogus'" err.txt || fail "tailsim $args does not name --bogus: $(cat err.txt)"
done
run 2 "$tailsim"
run 2 "$tailsim" mjcf --links 9 --out x.xml
[ ! -e x.xml ] || fail "mjcf --links 9 wrote x.xml"
run 0 "$tailsim" --help
for code in 0 1 2 3 130; do grep -Eq "^ +$code +[a-z]" out.txt || fail "--help does not document exit code $code"; done
ok "rn, --bogus, no subcommand, --links 9: exit 2; --help lists exit codes 0 1 2 3 130"

echo "== --case names a case (exit 1, lists the cases), before any work"
run 1 "$tailsim" render "$src/configs/default.yaml" --case nosuch --out rend
grep -q "no case named 'nosuch'" err.txt && grep -q "cases: base" err.txt || fail "render --case nosuch: $(cat err.txt)"
[ ! -e rend ] || fail "render --case nosuch created its output folder"
run 1 "$tailsim" run "$src/configs/paper/all.yaml" --case nosuch --out runout
grep -q "no case named 'nosuch'" err.txt || fail "run --case nosuch (suite): $(cat err.txt)"
[ ! -e runout ] || fail "run --case nosuch created its output folder"
ok "render/run --case nosuch: exit 1, '$(cut -c1-90 err.txt)...'"

echo "== a file given to the wrong command names the command that reads it (exit 1, or 2 for a folder argument), before any work"
opt="$src/configs/design/split_n1.yaml"
man="$src/configs/design/maneuver_90.yaml"
exp="$src/configs/default.yaml"
# want RC "COMMAND ARGS" "TEXT": exit RC, TEXT in stderr, no output folder/file made.
want() {
  run "$1" "$tailsim" $2
  grep -qF -- "$3" err.txt || fail "tailsim $2: stderr does not say '$3': $(cat err.txt)"
  [ ! -e wrongout ] || fail "tailsim $2 made its output before refusing"
}
for cmd in run render accuracy; do
  want 1 "$cmd $opt --out wrongout" "$opt is an optimize file: run it with \`tailsim optimize $opt --out DIR\`"
  want 1 "$cmd $man --out wrongout" "$man is a maneuver file: run it with \`tailsim maneuver $man --out DIR\`"
done
want 1 "mjcf $opt --out wrongout" "is an optimize file: run it with \`tailsim optimize"
want 1 "mjcf $man --menagerie wrongout" "is a maneuver file: run it with \`tailsim maneuver"
want 1 "run $robot --out wrongout" "is a robot file: name it in an experiment's robot: key"
want 1 "optimize $exp --out wrongout" "is an experiment file: run it with \`tailsim run $exp --out DIR\`"
want 1 "optimize $src/configs/paper/all.yaml --out wrongout" "is an experiment file: run it with \`tailsim run"
want 1 "optimize $man --out wrongout" "is a maneuver file: run it with \`tailsim maneuver"
want 1 "maneuver $exp --out wrongout" "is an experiment file: run it with \`tailsim run"
want 1 "maneuver $opt --out wrongout" "is an optimize file: run it with \`tailsim optimize"
for cmd in plot report ladder; do
  want 2 "$cmd $exp" "is an experiment file: run it with \`tailsim run $exp --out DIR\`, then give DIR"
  want 2 "$cmd $opt" "is an optimize file: run it with \`tailsim optimize"
done
printf 'name: typo\nrobot: paper\ntrajectroy: {dtheta_deg: -90, dT_s: 0.25}\n' >typo.yaml
want 1 "run typo.yaml --out wrongout" "trajectroy: unknown key; did you mean 'trajectory'?"
sed 's/^  islands:/  islnds:/' "$src/configs/design/start_here_split_cycle.yaml" | sed "s|base: base/|base: $src/configs/design/base/|" >typo_opt.yaml
want 1 "optimize typo_opt.yaml --out wrongout" "optimize.islnds: unknown key; did you mean 'islands'?"
ok "run/render/accuracy/mjcf/optimize/maneuver/plot/report/ladder name the right command; 'did you mean' for a misspelt key"

echo "== failed model runs: exit 3; tailsim_version in summary.json"
printf 'name: tipping\nrobot: %s\ntail: {custom: [{mass_kg: 50, izz_kgm2: 0.5, length_m: 0.3}]}\n' "$robot" >tip.yaml
printf 'trajectory: {theta0_deg: 0, dtheta_deg: -90, dT_s: 0.25, w_ss: 0.25}\nmodels: [analytic]\n' >>tip.yaml
run 3 "$tailsim" run tip.yaml --out tip --quiet
grep -q "1 failed model runs" out.txt || fail "run with a failing model run: $(cat out.txt)"
grep -q "\"tailsim_version\": \"$version\"" tip/summary.json || fail "tip/summary.json has no tailsim_version $version"
ok "a tipping robot: exit 3, summary.json tailsim_version $version"

echo "== user-named outputs are written through, never replaced"
run 0 "$tailsim" mjcf --links 2 --out -
grep -q "^<mujoco model=" out.txt || fail "mjcf --out - did not write the XML to stdout"
tail -n 2 out.txt | grep -q "</mujoco>" || fail "mjcf --out -: stdout is not only the XML: $(tail -n 2 out.txt)"
grep -q "^wrote" out.txt && fail "mjcf --out -: a message went into the XML on stdout"
cp out.txt expected2.xml
run 0 "$tailsim" mjcf --links 2 --out /dev/null
[ -c /dev/null ] || fail "/dev/null is no longer a character device"
echo "kept line" >appended.txt
rc=0
"$tailsim" mjcf --links 2 --out /dev/stdout >>appended.txt 2>err.txt || rc=$?
[ $rc -eq 0 ] || fail "mjcf --out /dev/stdout: exit $rc: $(cat err.txt)"
[ -L /dev/stdout ] || fail "/dev/stdout is no longer a symlink"
[ "$(head -n 1 appended.txt)" = "kept line" ] || fail "mjcf --out /dev/stdout >> file truncated the file"
cmp -s <(tail -n +2 appended.txt) expected2.xml || fail "mjcf --out /dev/stdout >> file: not the XML appended"
: >target.xml
ln -s target.xml link.xml
run 0 "$tailsim" mjcf --links 2 --out link.xml
[ -L link.xml ] || fail "mjcf --out link.xml replaced the symlink"
cmp -s target.xml expected2.xml || fail "mjcf --out link.xml did not write the link's target"
run 0 "$tailsim" mjcf --links 2 --out plain.xml
cmp -s plain.xml expected2.xml || fail "mjcf --out plain.xml differs from the stdout XML"
mkdir adir
run 1 "$tailsim" mjcf --links 2 --out adir
[ -d adir ] || fail "mjcf --out DIR replaced the folder"
run 0 "$tailsim" mjcf --links 1 --out plain.xml
grep -q 'model="tailsim_quadruped_tail1"' plain.xml || fail "mjcf --out plain.xml did not replace tailsim's own file"
printf '<mujoco model="mine"/>\n' >mine.xml
cp mine.xml mine.orig
ln -s mine.xml minelink.xml
for target in mine.xml minelink.xml; do
  run 1 "$tailsim" mjcf --links 2 --out $target
  grep -q "was not written by tailsim: not replaced" err.txt || fail "mjcf --out over a user's file $target: $(cat err.txt)"
  cmp -s mine.xml mine.orig || fail "mjcf --out $target replaced the user's model file"
done
ok "mjcf --out: - (XML only), /dev/null, /dev/stdout >> file (appended), symlink (kept, target written), folder (error), tailsim's own file replaced, a user's file (or its link) refused and kept"

echo "== mjcf of an experiment: a custom tail as one file (= the result folder's model) and in Menagerie form"
printf 'name: custom3\nrobot: %s\n' "$robot" >custom3.yaml
printf 'tail: {custom: [{mass_kg: 1.1, izz_kgm2: 0.004, length_m: 0.14}, {mass_kg: 0.7, izz_kgm2: 0.002, length_m: 0.11}, {mass_kg: 0.45, izz_kgm2: 0.0007, length_m: 0.09}]}\n' >>custom3.yaml
printf 'trajectory: {theta0_deg: 0, dtheta_deg: -30, dT_s: 0.3, w_ss: 0.3}\nmodels: [mujoco]\noutput: {duration_s: 0.2}\n' >>custom3.yaml
run 0 "$tailsim" mjcf custom3.yaml --out custom3.xml
run 0 "$tailsim" run custom3.yaml --out custom3_run --models mujoco --no-render --quiet
ls custom3_run/mjcf/*.xml >/dev/null 2>&1 || fail "run custom3.yaml wrote no mjcf/<hash>.xml"
cmp -s custom3.xml custom3_run/mjcf/*.xml || fail "mjcf custom3.yaml --out differs from the model the run simulated"
run 0 "$tailsim" mjcf custom3.yaml --menagerie men
[ -s men/tailsim_custom3.xml ] && [ -s men/scene_custom3.xml ] || fail "mjcf --menagerie men: $(ls men)"
grep -q 'm_L,i = \[1.1, 0.7, 0.45\] kg' men/tailsim_custom3.xml || fail "the robot file's comment does not list the link masses"
grep -q '<include file="tailsim_custom3.xml"/>' men/scene_custom3.xml || fail "the scene does not include the robot file"
msg=$(mujoco-compile men/scene_custom3.xml model.txt 2>&1 </dev/null)
grep -q Done <<<"$msg" || fail "MuJoCo cannot compile men/scene_custom3.xml: $msg"
grep -Eq "^ *nu +3$" model.txt || fail "men/scene_custom3.xml does not have 3 tail actuators"
run 2 "$tailsim" mjcf custom3.yaml
grep -q -- "--out FILE or --menagerie DIR" err.txt || fail "mjcf without --out/--menagerie: $(cat err.txt)"
run 1 "$tailsim" mjcf "$src/configs/paper/all.yaml" --out many.xml
grep -q "distinct MuJoCo models" err.txt || fail "mjcf of a many-model suite with --out: $(cat err.txt)"
run 1 "$tailsim" mjcf custom3.yaml --case nosuch --out x.xml
ok "mjcf EXPERIMENT: --out = the run's mjcf/<hash>.xml; --menagerie: robot + scene, compiles (nu 3); usage and many-model errors"

echo "== progress in a log (stderr not a TTY): plain lines, no carriage returns"
printf 'name: wss_sweep\nrobot: %s\ntail: {links: 1}\n' "$robot" >sweep.yaml
printf 'trajectory: {theta0_deg: 45, dtheta_deg: -90, dT_s: 0.25, w_ss: {range: [0.1, 0.9, 0.03]}}\n' >>sweep.yaml
printf 'models: [mujoco]\n' >>sweep.yaml
run 0 "$tailsim" run sweep.yaml --out log_run --threads 2 --models mujoco
total=$(sed -n 's/^\([0-9]*\) cases: .*/\1/p' out.txt)
[ "${total:-0}" -ge 20 ] || fail "sweep.yaml has ${total:-0} cases, want >= 20: $(head -n 2 out.txt)"
grep -q $'\r' err.txt && fail "progress in a log contains carriage returns"
grep -Eq "^\[wss_sweep\] $total/$total cases \(0 resumed\), [0-9.]+ s elapsed$" err.txt ||
  fail "no final progress line in the log: $(cat err.txt)"
ok "progress in a log: '$(tail -n 1 err.txt)', no \\r"

echo "== Ctrl-C: running cases finish, the count saved is printed, exit 130, a rerun resumes"
set -m  # job control: the background run gets SIGINT like a foreground one (not ignored)
"$tailsim" run sweep.yaml --out int_run --threads 1 >out.txt 2>err.txt &
pid=$!
for _ in $(seq 1 600); do  # until the first case is saved (the run is under way), at most 60 s
  [ -n "$(find int_run/cases -name result.json 2>/dev/null | head -n 1)" ] && break
  sleep 0.1
done
kill -INT "$pid"
rc=0
wait "$pid" || rc=$?
set +m
[ $rc -eq 130 ] || fail "exit $rc after Ctrl-C (want 130)\n$(cat err.txt)"
grep -Eq "^interrupted: finishing [01] running cases? \(Ctrl-C again to abandon" err.txt || fail "no 'finishing' message: $(cat err.txt)"
saved=$(sed -n 's/^interrupted: \([0-9]*\) of \([0-9]*\) cases saved in int_run; run the same command again to resume$/\1/p' err.txt)
[ -n "$saved" ] || fail "no 'N of M cases saved' message: $(cat err.txt)"
[ "$saved" -ge 1 ] && [ "$saved" -lt "$total" ] || fail "$saved of $total saved after an early Ctrl-C"
files=$(find int_run/cases -name result.json | wc -l)
[ "$files" -eq "$saved" ] || fail "$files result.json files, but the message says $saved saved"
grep -q '"cases"' int_run/summary.json || fail "no summary.json after Ctrl-C"
said=$(tail -n 1 err.txt)
run 0 "$tailsim" run sweep.yaml --out int_run --threads 2 --quiet
grep -q "^$total cases: $((total - saved)) run, $saved resumed, 0 failed" out.txt || fail "rerun: $(head -n 1 out.txt)"
ok "Ctrl-C after the first case: exit 130, '$said', rerun resumed $saved"

echo "== SIGTERM during optimize: the seeds that finished are the result, exit 143"
cat >opt_sig.yaml <<EOF
name: opt_sig
kind: optimize
base: $src/configs/design/base/eq25_n1.yaml
optimize:
  family: split_cycle
  objective: phi_net
  limits: {theta_deg: [-90, 90], thetadot_max_dps: 600, torque_max_Nm: none}
  islands: 1
  population: 8
  generations: 200
  seeds: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12]
  mujoco_check: false
EOF
"$tailsim" optimize opt_sig.yaml --out opt_sig >out.txt 2>err.txt &
pid=$!
for _ in $(seq 1 600); do  # until the first seed has finished, at most 60 s
  grep -q "^seed 1: " err.txt && break
  sleep 0.1
done
kill -TERM "$pid"
rc=0
wait "$pid" || rc=$?
[ $rc -eq 143 ] || fail "optimize: exit $rc after SIGTERM (want 143)\n$(tail -n 3 err.txt)"
grep -Eq "^optimize opt_sig: stopped by SIGTERM after [0-9]+ of 12 seeds: the best of those is written" err.txt ||
  fail "optimize: no stop message: $(tail -n 3 err.txt)"
grep -q '"stopped_by": "SIGTERM"' opt_sig/summary.json || fail "optimize: summary.json does not say it was stopped"
[ -f opt_sig/best.yaml ] || fail "optimize: no best.yaml after SIGTERM"
ok "optimize: SIGTERM after the first seed: exit 143, $(grep -o 'after [0-9]* of 12 seeds' err.txt), summary.json stopped_by"

echo "== Ctrl-C twice with every series in one HDF5 file: the finished cases stay resumable"
sed 's/^name: wss_sweep/name: wss_sweep_h5/' sweep.yaml >sweep_h5.yaml
# 4 s simulated per case: the case running at the first Ctrl-C is still running at the second.
printf 'output: {time_series_file: hdf5, duration_s: 4}\n' >>sweep_h5.yaml
set -m
"$tailsim" run sweep_h5.yaml --out int_h5 --threads 1 >out.txt 2>err.txt &
pid=$!
for _ in $(seq 1 600); do  # until 2 cases are in the journal, at most 60 s
  [ "$(wc -l <int_h5/cases.jsonl 2>/dev/null || echo 0)" -ge 2 ] && break
  sleep 0.1
done
kill -INT "$pid"
for _ in $(seq 1 100); do  # the first Ctrl-C answered ("finishing ..."), at most 10 s
  grep -q "^interrupted: finishing" err.txt && break
  sleep 0.1
done
kill -INT "$pid" 2>/dev/null || true
rc=0
wait "$pid" || rc=$?
set +m
[ $rc -eq 130 ] || fail "exit $rc after two Ctrl-C (want 130)\n$(cat err.txt)"
grep -q "^interrupted again: abandoning the running cases; [0-9]* cases saved" err.txt || fail "no 'abandoning' message: $(cat err.txt)"
saved=$(sed -n 's/^interrupted again: abandoning the running cases; \([0-9]*\) cases saved$/\1/p' err.txt)
# (each finished case's groups are in a file of their own, time_series.h5.d/<case>.h5, before its journal line)
n_h5=$(ls int_h5/time_series.h5.d 2>/dev/null | grep -c '\.h5$' || true)
[ "$n_h5" -ge "$saved" ] || fail "two Ctrl-C: $saved cases saved but $n_h5 in time_series.h5.d: $(ls int_h5)"
run 0 "$tailsim" run sweep_h5.yaml --out int_h5 --threads 2 --quiet
resumed=$(sed -n 's/^[0-9]* cases: [0-9]* run, \([0-9]*\) resumed.*/\1/p' out.txt)
[ "${resumed:-0}" -ge "$saved" ] && [ "$saved" -ge 1 ] || fail "$saved saved, but the rerun resumed ${resumed:-0}: $(head -n 1 out.txt)"
ok "two Ctrl-C with HDF5 output: '$saved cases saved', the rerun resumed $resumed"

echo "== --models, --shard, --threads: nothing silently empty, usage errors exit 2"
run 1 "$tailsim" run "$src/configs/default.yaml" --out models_none --models perfoot
grep -q "none of those its cases run (analytic): nothing would run" err.txt || fail "--models perfoot on an analytic experiment: $(cat err.txt)"
[ ! -e models_none/results.csv ] || fail "--models selecting nothing still wrote results"
run 2 "$tailsim" run "$src/configs/default.yaml" --out r --models mujocoo
for sh in 5/4 0/4 abc; do
  run 2 "$tailsim" run "$src/configs/default.yaml" --out r --shard "$sh"
  grep -q -- "--shard $sh: want K/N" err.txt || fail "--shard $sh: $(cat err.txt)"
done
run 2 "$tailsim" run "$src/configs/default.yaml" --out r --threads -1
run 2 "$tailsim" accuracy "$src/configs/accuracy/fig07.yaml" --out r --repeats 0
ok "--models selecting nothing exits 1 and writes nothing; bad --shard/--threads/--repeats exit 2"

# tailsim trust: a case it does not have, or a folder of `tailsim run`, is refused before any work.
run 1 "$tailsim" trust "$src/configs/examples/robot_12kg_n3.yaml" --out trust_nope --case nope
grep -q "no case named 'nope'" err.txt || fail "trust --case nope: $(cat err.txt)"
[ ! -e trust_nope ] || fail "trust --case nope made its folder"
run 2 "$tailsim" trust "$src/configs/examples/robot_12kg_n3.yaml"
ok "tailsim trust: an unknown --case exits 1 and makes no folder; no --out exits 2"

# A run that renders nothing does not load OSMesa (LLVM, z3, ICU) at all.
LD_DEBUG=libs "$tailsim" run "$src/configs/default.yaml" --out lazy_gl --quiet >out.txt 2>err.txt || fail "lazy-GL run: $(tail -3 err.txt)"
grep -q "calling init: .*libyaml-cpp" err.txt || fail "LD_DEBUG=libs printed no library list: cannot check OSMesa"
! grep -q "libOSMesa\|libLLVM" err.txt || fail "an analytic run loaded OSMesa/LLVM: $(grep -m1 'libOSMesa\|libLLVM' err.txt)"
ok "an analytic run starts without OSMesa/LLVM (LD_DEBUG=libs)"

echo "PASS"
