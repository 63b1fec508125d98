#!/usr/bin/env bash
# What a reader of the paper suite's figures sees, checked on a folder `tailsim run
# configs/paper/all.yaml --plot` (or `tailsim plot`) wrote:
#   - every figure of the paper suite exists (the list below), and every figure is non-blank:
#     PNG signature, > 8 KB, width/height in the IHDR chunk as its .gp script's pngcairo size;
#   - no title is a file or experiment name (titles read from the .gp scripts: no folder name,
#     plot stem or .dat/.csv/.png file in them; every figure's title starts with "Fig.");
#   - DIR/figures.html shows every PNG under DIR/*/plots/ exactly once, with a caption;
#   - no axis is a case index (tests/check_axes.sh).
#   tests/check_figures.sh DIR          (called by readme_tour_test.sh on results/paper)
set -euo pipefail
dir=$1
fail() { printf 'FAIL (check_figures): %b\n' "$*"; exit 1; }

expected=(
  fig06a_model_comparison_1dof/plots/fig06a_model_comparison_1dof_phi
  fig06a_model_comparison_1dof/plots/fig06a_model_comparison_1dof_moments
  fig06b_model_comparison_6dof/plots/fig06b_model_comparison_6dof_phi
  fig06b_model_comparison_6dof/plots/fig06b_model_comparison_6dof_moments
  fig07_loading/plots/fig07_loading_phi
  fig07_loading/plots/fig07_loading_moments
  fig08_moment_contributions/plots/fig08_moment_contributions_contributions
  fig08_moment_contributions/plots/fig08_moment_contributions_LF
  fig09_theta0_dQ2B/plots/fig09_theta0_dQ2B_phi_net_map
  fig09_theta0_dQ2B/plots/fig09_theta0_dQ2B_phi_net_lines
  fig10_LF/plots/fig10_LF_LF_map
  fig11_wss/plots/fig11_wss_phi_net
  fig11_wss/plots/fig11_wss_phi_t
  fig12_dT_dtheta/plots/fig12_dT_dtheta_phi_net_map
  fig12_dT_dtheta/plots/fig12_dT_dtheta_phi_net_lines
  fig13_equal_peak_speed/plots/fig13_equal_peak_speed_phi_net
  fig13_equal_peak_speed/plots/fig13_equal_peak_speed_phi_t
  fig14_tail_dof/plots/fig14_tail_dof_phi_net
  fig14_tail_dof/plots/fig14_tail_dof_phi_t
  mu_swapped/plots/mu_swapped_phi
  mu_swapped/plots/mu_swapped_moments
  model_bridge_n1/plots/model_bridge_n1_phi_net_bars
  model_bridge_n6/plots/model_bridge_n6_phi_net_bars
)
for e in "${expected[@]}"; do
  [ -f "$dir/$e.png" ] || fail "missing figure $dir/$e.png"
done

# Big-endian 32-bit integer at byte offset $2 of file $1.
be32() { od -An -tu1 -j"$2" -N4 "$1" | awk '{ print ((($1 * 256 + $2) * 256 + $3) * 256 + $4) }'; }

n=0
while IFS= read -r gp; do
  png=${gp%.gp}.png
  stem=$(basename "${gp%.gp}")
  exp=$(basename "$(dirname "$(dirname "$gp")")")
  [ -f "$png" ] || fail "$gp has no PNG"
  [ "$(head -c 8 "$png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || fail "$png is not a PNG"
  size=$(stat -c %s "$png")
  [ "$size" -gt 8000 ] || fail "$png is $size bytes: blank?"
  read -r w h < <(sed -n "s/^set terminal pngcairo .*size \([0-9]*\),\([0-9]*\).*/\1 \2/p" "$gp")
  [ "$(be32 "$png" 16)" = "$w" ] && [ "$(be32 "$png" 20)" = "$h" ] ||
    fail "$png is $(be32 "$png" 16)x$(be32 "$png" 20), its script says ${w}x$h"
  # Titles: `set title '...'` and `set multiplot ... title '...'`; the figure's own title is the first.
  # (gpQuote writes a quote inside the text as '."'".': read back as ')
  titles=$(grep -oE "^set (title|multiplot .* title) '([^']|'\.\"'\"\.')*'" "$gp" |
           sed -E "s/^set (title|multiplot .* title) '//; s/'\$//; s/'\.\"'\"\.'/'/g")
  [ -n "$titles" ] || fail "$gp has no title"
  first=$(head -n1 <<<"$titles")
  [[ "$first" == Fig.* ]] || fail "$gp: title '$first' does not name the paper's figure"
  while IFS= read -r t; do
    for bad in "$exp" "$stem" ".dat" ".csv" ".png"; do
      [[ "$t" != *"$bad"* ]] || fail "$gp: title '$t' contains the name '$bad'"
    done
  done <<<"$titles"
  n=$((n + 1))
done < <(find "$dir" -path '*/plots/*.gp' | sort)
[ "$n" -ge ${#expected[@]} ] || fail "only $n figure scripts under $dir"

sheet=$dir/figures.html
[ -s "$sheet" ] || fail "no $sheet"
listed=$(grep -oE '<img src="[^"]*"' "$sheet" | sed -E 's/<img src="//; s/"$//' | sort)
actual=$(cd "$dir" && find . -path '*/plots/*.png' | sed 's|^\./||' | sort)
[ "$listed" = "$actual" ] || fail "figures.html lists:\n$listed\nbut the PNGs are:\n$actual"
[ "$(grep -c '<figcaption>' "$sheet")" = "$(wc -l <<<"$actual")" ] || fail "figures.html: a figure without caption"
echo "  ok: $n figures under $dir: non-blank, sized as scripted, titled in words; figures.html lists all"
bash "$(dirname "$0")/check_axes.sh" "$dir"
