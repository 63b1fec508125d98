#!/usr/bin/env bash
# The README's "Quick tour", verbatim, is a test: the command block is read from README.md at test
# time (the first ``` block after the first heading matching /tour/i, as the docs hook does), every
# command runs in a temporary copy of the repository from its root with the README's relative
# paths, and what each command promises is checked. Then run/plot/mjcf/accuracy again from a
# subfolder with ../ paths (relative result folders from another working directory).
#   tests/readme_tour_test.sh SOURCE_DIR BUILD_DIR      (CTest: readme_tour)
set -euo pipefail
src=$(cd "$1" && pwd)
bld=$(cd "$2" && pwd)
[ -x "$bld/tailsim" ] || { echo "FAIL: $bld/tailsim not built"; exit 1; }

fail() { printf 'FAIL: %b\n' "$*"; exit 1; }
ok() { echo "  ok: $*"; }

tour=$(awk 'BEGIN { h = 0; inb = 0 }
  !h && /^#/ && tolower($0) ~ /tour/ { h = 1; next }
  h && /^```/ { if (inb) exit; inb = 1; next }
  inb { print }' "$src/README.md")
[ -n "$tour" ] || fail "no command block under a 'tour' heading in README.md"

work=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_tour.XXXXXX")
trap 'rm -rf "$work"' EXIT
repo="$work/repo"
mkdir "$repo"
# A copy of the repository as a user has it after building: sources and configs, build/ = this build.
(cd "$src" && tar cf - --exclude=./build --exclude=./.git --exclude=./results --exclude='./renders/*' .) |
  (cd "$repo" && tar xf -)
ln -s "$bld" "$repo/build"

is_png() { [ -s "$1" ] && [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ]; }
frames() { ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 "$1"; }

# Value of option $1 in the words that follow (empty if absent).
opt() {
  local name=$1; shift
  while [ $# -gt 0 ]; do
    if [ "$1" = "$name" ] && [ $# -gt 1 ]; then echo "$2"; return; fi
    shift
  done
}

# Checks what `tailsim <words>` promises, from the working directory it ran in; $out = its stdout.
check() {
  local out=$1; shift
  local sub=$2
  local pos=$3  # first positional argument after the subcommand
  case "$sub" in
    run)
      local dir; dir=$(opt --out "$@")
      local sums; sums=$(find "$dir" -name summary.json | wc -l)
      [ "$sums" -ge 1 ] || fail "run: no summary.json under $dir"
      for s in $(find "$dir" -name summary.json); do
        grep -q '"tailsim_version"' "$s" || fail "run: $s has no tailsim_version"
      done
      grep -q "cases: .* run, .* resumed, 0 failed model runs" <<<"$out" || fail "run: no '0 failed' summary line:\n$out"
      ok "run -> $dir: $sums summary.json"
      if printf '%s\n' "$@" | grep -qx -- --plot; then
        [ -s "$dir/report.md" ] || fail "run --plot: no $dir/report.md"
        local n; n=$(find "$dir" -path '*/plots/*.png' -size +1k | wc -l)
        [ "$n" -ge 1 ] || fail "run --plot: no plots under $dir"
        [ -s "$dir/figures.html" ] || fail "run --plot: no $dir/figures.html"
        [ -s "$dir/index.html" ] && [ -s "$dir/page/data.js" ] || fail "run --plot: no result page $dir/index.html"
        ok "run --plot: report.md, figures.html, index.html and $n PNG plots"
      fi
      ;;
    plot)
      local n=0
      while read -r f; do
        [ -n "$f" ] || continue
        [ "$f" = "$pos/figures.html" ] && continue
        if [ "$f" = "$pos/index.html" ]; then
          grep -q 'src="page/data.js"' "$f" || fail "plot: $f (printed) is not the result page"
          continue
        fi
        is_png "$f" || fail "plot: $f (printed) is not a PNG"
        grep -qF "<img src=\"${f#"$pos"/}\"" "$pos/figures.html" || fail "plot: $pos/figures.html does not show $f"
        n=$((n + 1))
      done <<<"$out"
      [ "$n" -ge 1 ] || fail "plot: printed no PNG"
      [ "$(tail -n1 <<<"$out")" = "$pos/figures.html" ] || fail "plot: the figure sheet $pos/figures.html not printed last"
      ok "plot $pos: $n PNGs and figures.html"
      ;;
    report)
      [ "$(tail -n1 <<<"$out")" = "$pos/report.md" ] || fail "report: printed '$out', not $pos/report.md"
      [ -s "$pos/report.md" ] || fail "report: $pos/report.md is empty or missing"
      grep -q '\.png' "$pos/report.md" || fail "report: $pos/report.md shows no figure"
      ok "report: $pos/report.md"
      ;;
    render)
      local dir; dir=$(opt --out "$@")
      [ -n "$dir" ] || dir=renders
      local n=0
      for mp4 in $(find "$dir" -name '*.mp4'); do
        local fr; fr=$(frames "$mp4")
        [ "$fr" -gt 1 ] || fail "render: $mp4 has $fr frames"
        is_png "${mp4%.mp4}.png" || fail "render: no PNG beside $mp4"
        grep -q "$mp4: $fr frames" <<<"$out" || fail "render: printed frame count differs from $mp4's $fr"
        n=$((n + 1))
      done
      [ "$n" -ge 1 ] || fail "render: no MP4 under $dir"
      ok "render: $n MP4 + PNG ($fr frames)"
      ;;
    mjcf)
      local f; f=$(opt --out "$@")
      local links; links=$(opt --links "$@")
      local men; men=$(opt --menagerie "$@")
      if [ -n "$men" ]; then  # Menagerie form: every scene compiles (its robot file included)
        local scenes; scenes=$(find "$men" -name 'scene_*.xml' | sort)
        [ -n "$scenes" ] || fail "mjcf --menagerie $men: no scene_*.xml"
        for sc in $scenes; do
          local robotf; robotf="$men/tailsim_$(basename "$sc" | sed 's/^scene_//')"
          [ -s "$robotf" ] || fail "mjcf --menagerie: $sc without its robot file $robotf"
          rm -f "$work/model.txt"
          local msg; msg=$(mujoco-compile "$sc" "$work/model.txt" 2>&1 </dev/null)
          grep -q Done <<<"$msg" || fail "mjcf: MuJoCo cannot compile $sc: $msg"
        done
        ok "mjcf --menagerie: $(wc -w <<<"$scenes") scene(s) in $men compile with their robot files"
        return
      fi
      rm -f "$work/model.txt"
      local msg; msg=$(mujoco-compile "$f" "$work/model.txt" 2>&1 </dev/null)
      grep -q Done <<<"$msg" || fail "mjcf: MuJoCo cannot compile $f: $msg"
      grep -Eq "^ *nu +${links:-1}$" "$work/model.txt" || fail "mjcf: $f does not have ${links:-1} tail actuators"
      ok "mjcf: $f compiles in MuJoCo with ${links:-1} tail motors"
      ;;
    accuracy)
      local dir; dir=$(opt --out "$@")
      [ -s "$dir/accuracy.md" ] || fail "accuracy: no $dir/accuracy.md"
      grep -q '| analytic |' "$dir/accuracy.md" || fail "accuracy: no analytic rows in $dir/accuracy.md"
      grep -q '| mujoco |' "$dir/accuracy.md" || fail "accuracy: no mujoco rows in $dir/accuracy.md"
      [ "$(wc -l <"$dir/accuracy.csv")" -gt 2 ] || fail "accuracy: $dir/accuracy.csv has no rows"
      local png; png=$(grep '\.png$' <<<"$out" | head -n1)
      is_png "$png" || fail "accuracy: printed plot '$png' is not a PNG"
      ok "accuracy: $dir/accuracy.md, accuracy.csv ($(($(wc -l <"$dir/accuracy.csv") - 1)) rows), $png"
      ;;
    *) fail "README tour command '$sub' has no check in $0: add one" ;;
  esac
}

# Runs one command line (as written: relative paths, comments) in the current directory.
run_line() {
  local line=$1
  local words
  read -ra words <<<"${line%%#*}"
  [ ${#words[@]} -gt 0 ] || return 0
  echo "\$ $line"
  local out rc=0
  out=$(bash -c "$line" 2>"$work/stderr") || rc=$?
  [ $rc -eq 0 ] || fail "exit $rc from: $line\n$(tail -n 20 "$work/stderr")"
  check "$out" "${words[@]}"
}

echo "== README Quick tour, from the repository root"
cd "$repo"
n=0
while IFS= read -r line; do
  case "$line" in build/tailsim*) ;; "" | \#*) continue ;; *) fail "tour line does not start with build/tailsim: $line" ;; esac
  run_line "$line"
  n=$((n + 1))
done <<<"$tour"
[ "$n" -ge 7 ] || fail "only $n tour commands found in README.md"
# The paper suite's figures as a reader sees them (every figure, non-blank, titles in words, sheet).
[ -d results/paper ] || fail "the tour wrote no results/paper"
bash "$src/tests/check_figures.sh" results/paper

echo "== the same kinds of commands from a subfolder, with ../ paths"
mkdir -p "$repo/elsewhere"
cd "$repo/elsewhere"
run_line "../build/tailsim run ../configs/default.yaml --out ../results/from_sub --plot"
run_line "../build/tailsim plot ../results/from_sub"
run_line "../build/tailsim mjcf --links 2 --out ../tail2.xml"
run_line "../build/tailsim accuracy ../configs/accuracy/fig07.yaml --out ../results/acc_sub --quick --repeats 1"
echo "PASS: $n README tour commands and 4 from a subfolder"
