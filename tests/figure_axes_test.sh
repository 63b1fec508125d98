#!/usr/bin/env bash
# Every figure tailsim draws for a sweep of any shape reads its axes as swept keys, never as a case
# index (tests/check_axes.sh): random sweeps of 1 to 4 keys (numeric and categorical, 2-4 values
# each) on a robot that is not the paper's (tests/data/figure_robot.yaml), analytic and per-foot
# models, run with `tailsim run --quiet` and drawn with `tailsim plot`. Seed 36 unless
# TAILSIM_FIGURE_SEED says another (printed, to replay a failure). Also checks what the 3+-key
# figures are (one small-multiples figure per model), that --quiet prints one line, and
# `plot --no-titles --size W,H --font-scale F`.
#   tests/figure_axes_test.sh SRC BUILD
set -euo pipefail
src=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
tailsim=$build/tailsim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { printf 'FAIL (figure_axes): %b\n' "$*"; exit 1; }
seed=${TAILSIM_FIGURE_SEED:-36}
echo "seed $seed"
RANDOM=$seed

# key: values (YAML flow list); categorical keys last two
keys=(
  "trajectory.dtheta_deg:[-60, -120, -180]"
  "trajectory.dT_s:[0.2, 0.35, 0.5, 0.65]"
  "trajectory.w_ss:[0.15, 0.5]"
  "trajectory.theta0_deg:[0, 45, 90]"
  "quadruped.d_Q2B_m:[0.06, 0.12]"
  "tail.links:[1, 2]"
  "effects.friction:[stiction, continuous]"
)
for run in 1 2 3 4; do
  nkeys=$(( (run - 1) % 4 + 1 ))   # 1, 2, 3, 4 keys
  # pick nkeys distinct keys
  picked=()
  while [ ${#picked[@]} -lt "$nkeys" ]; do
    k=${keys[$((RANDOM % ${#keys[@]}))]}
    dup=0
    for p in "${picked[@]+"${picked[@]}"}"; do [ "$p" = "$k" ] && dup=1; done
    [ $dup = 1 ] || picked+=("$k")
  done
  exp=$work/sweep$run.yaml
  {
    echo "name: random_sweep_$run"
    echo "description: \"random sweep $run of $nkeys keys on a robot of our own\""
    echo "robot: $src/tests/data/figure_robot.yaml"
    echo "kind: simulate"
    echo "models: [analytic, perfoot]"
    declare -A sections=([tail]="links: 1" [trajectory]="theta0_deg: 60, dtheta_deg: -120, dT_s: 0.3, w_ss: 0.25"
                         [quadruped]="" [effects]="")
    for p in "${picked[@]}"; do
      full=${p%%:*}; vals=${p#*:}; sec=${full%%.*}; key=${full#*.}
      cur=${sections[$sec]}
      # drop the fixed value of a swept key, then add the sweep
      cur=$(sed -E "s/(^|, )$key: [^,]*//; s/^, //" <<<"$cur")
      sections[$sec]="${cur:+$cur, }$key: {sweep: $vals}"
    done
    for sec in tail trajectory quadruped effects; do
      [ -n "${sections[$sec]}" ] && echo "$sec: {${sections[$sec]}}"
    done
  } >"$exp"
  echo "--- sweep $run: ${picked[*]}"
  out=$work/out$run
  lines=$("$tailsim" run "$exp" --out "$out" --no-render --quiet --threads 2 | wc -l)
  [ "$lines" = 1 ] || fail "sweep $run: tailsim run --quiet printed $lines lines on stdout"
  "$tailsim" plot "$out" >"$work/plot$run.txt"
  sed 's|.*/||' "$work/plot$run.txt"
  bash "$src/tests/check_axes.sh" "$out"
  if [ "$nkeys" -ge 3 ]; then
    for m in analytic perfoot; do
      [ -f "$out/plots/random_sweep_${run}_phi_net_facets_$m.png" ] || fail "sweep $run: no small-multiples figure for $m"
    done
  fi
done

# For a paper or slides: no figure title in the image (the caption keeps it), one size, bigger fonts.
"$tailsim" plot "$work/out1" --no-titles --size 800,600 --font-scale 1.5 >/dev/null
for gp in "$work"/out1/plots/*.gp; do
  first=$(grep -oE "^set (title|multiplot .* title) '([^']|'')*'" "$gp" | head -n1)
  [[ "$first" == *"title ''" ]] || fail "$gp: --no-titles, but the figure's title is: $first"
  grep -q "^set terminal pngcairo enhanced size 800,600 font 'Sans,15' fontscale 1.5 " "$gp" ||
    fail "$gp: --size 800,600 --font-scale 1.5 not in the terminal line"
done
grep -q '<figcaption>' "$work/out1/figures.html" || fail "figures.html lost its captions"
echo "figure_axes: ok"
