#!/usr/bin/env bash
# No figure under DIR draws a case index on an axis: every gnuplot script (DIR/**/plots/*.gp) sets
# an x label, and no x or y label (nor x2/y2) mentions "case" ("case index (order of summary.json)",
# "case (ladder.csv order)"): the axes are the swept keys, time or the rungs, in words with units.
#   tests/check_axes.sh DIR      (tests/check_figures.sh and tests/figure_axes_test.sh call it)
set -euo pipefail
dir=$1
fail() { printf 'FAIL (check_axes): %b\n' "$*"; exit 1; }
n=0
while IFS= read -r -d '' gp; do
  n=$((n + 1))
  grep -Eq "^[[:space:]]*set xlabel '[^']+" "$gp" || fail "$gp sets no x label"
  if bad=$(grep -Ein "^[[:space:]]*set (x|y|x2|y2)label .*case" "$gp"); then
    fail "$gp: an axis is a case index:\n$bad"
  fi
done < <(find "$dir" -path '*/plots/*.gp' -print0)
[ "$n" -gt 0 ] || fail "no gnuplot script under $dir"
echo "check_axes: $n figures, every axis a swept key, time or a quantity"
