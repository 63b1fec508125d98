#!/usr/bin/env bash
# The README's three pictures, regenerated from the code: runs the paper experiments they come
# from (analytic + MuJoCo) into a temporary folder, draws their figures with `tailsim --plot`,
# redraws the three at a small size and copies them to docs/images/. docs/images/SOURCES.txt
# records, per image, the SHA-256 of its gnuplot script and of every .dat file the script reads.
#
#   scripts/readme_images.sh [BUILD_DIR]            regenerate docs/images/*.png and SOURCES.txt
#   scripts/readme_images.sh --check [BUILD_DIR]    regenerate the data only (not the PNGs) and
#                                                   fail if it differs from SOURCES.txt
#                                                   (CTest: readme_images_current)
# BUILD_DIR defaults to build/ (it must hold a built tailsim).
# Also docs/images/video_frame.png: the poster frame of `tailsim render` of Fig. 6a (640x480
# defaults; docs/rendering.md), recorded by the SHA-256 of the two time series it replays.
set -euo pipefail
check=0
if [ "${1:-}" = "--check" ]; then check=1; shift; fi
src=$(cd "$(dirname "$0")/.." && pwd)
bld=$(cd "${1:-$src/build}" && pwd)
tailsim=$bld/tailsim
[ -x "$tailsim" ] || { echo "error: $tailsim not built" >&2; exit 1; }
images=$src/docs/images

# image name | experiment file | figure stem (DIR/<experiment>/plots/<stem>.gp) | scale of the redraw
figures=(
  "fig06a_phi.png|fig06a_model_comparison_1dof|fig06a_model_comparison_1dof_phi|0.6"
  "fig07_moments.png|fig07_loading|fig07_loading_moments|0.6"
  "fig12_phi_net_map.png|fig12_dT_dtheta|fig12_dT_dtheta_phi_net_map|0.5"
)

work=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_readme_images.XXXXXX")
trap 'rm -rf "$work"' EXIT

declare -A ran=()
for f in "${figures[@]}"; do
  IFS='|' read -r _ exp _ _ <<<"$f"
  [ -n "${ran[$exp]:-}" ] && continue
  "$tailsim" run "$src/configs/paper/$exp.yaml" --out "$work/$exp" --plot --quiet >/dev/null
  ran[$exp]=1
done

# "<sha256>  <name>" of a figure's script and the .dat files it reads, names relative to plots/.
sources() {
  local plots=$1 stem=$2
  (cd "$plots" && {
    sha256sum "$stem.gp"
    grep -oE "'[^']*\.dat'" "$stem.gp" | tr -d "'" | sed 's,^\./,,' | sort -u | xargs sha256sum
  })
}

sheet=$work/SOURCES.txt
{
  echo "# docs/images: written by scripts/readme_images.sh from configs/paper/*.yaml (analytic + MuJoCo)."
  echo "# Per image: SHA-256 of its gnuplot script and of the data files it draws. The CTest"
  echo "# readme_images_current regenerates the data and compares; rerun the script when it fails."
  for f in "${figures[@]}"; do
    IFS='|' read -r image exp stem _ <<<"$f"
    echo "image $image <- configs/paper/$exp.yaml, figure $stem"
    sources "$work/$exp/plots" "$stem" | sed 's/^/  /'
  done
  echo "image video_frame.png <- configs/paper/fig06a_model_comparison_1dof.yaml, tailsim render, poster frame"
  (cd "$work/fig06a_model_comparison_1dof" && sha256sum cases/base/mujoco.csv cases/base/analytic.csv) | sed 's/^/  /'
} >"$sheet"

if [ $check = 1 ]; then
  if ! diff -u "$images/SOURCES.txt" "$sheet"; then
    echo "FAIL: docs/images are not current with the code: run scripts/readme_images.sh" >&2
    exit 1
  fi
  echo "ok: docs/images/SOURCES.txt matches the regenerated data of $(( ${#figures[@]} + 1 )) images"
  exit 0
fi

mkdir -p "$images"
for f in "${figures[@]}"; do
  IFS='|' read -r image exp stem scale <<<"$f"
  plots=$work/$exp/plots
  # The same script at a smaller size: PNG size and every font scaled; the SVG part is dropped.
  perl -ne '
    BEGIN { $s = shift @ARGV; $png = 0 }
    if (/^set terminal svg/) { last }
    s/size (\d+),(\d+)/"size " . int($1 * $s + 0.5) . "," . int($2 * $s + 0.5)/e;
    s/Sans,(\d+)/"Sans," . int($1 * $s * 1.25 + 0.5)/ge;
    s/set output .*/set output "small.png"/;
    print;' "$scale" "$plots/$stem.gp" >"$plots/small.gp"
  echo "unset output" >>"$plots/small.gp"
  (cd "$plots" && gnuplot small.gp)
  cp "$plots/small.png" "$images/$image.tmp"
  mv "$images/$image.tmp" "$images/$image"
  echo "$images/$image"
done
"$tailsim" render "$src/configs/paper/fig06a_model_comparison_1dof.yaml" --out "$work/video" >/dev/null
cp "$work/video/fig06a_model_comparison_1dof/base.png" "$images/video_frame.png.tmp"
mv "$images/video_frame.png.tmp" "$images/video_frame.png"
echo "$images/video_frame.png"
cp "$sheet" "$images/SOURCES.txt.tmp"
mv "$images/SOURCES.txt.tmp" "$images/SOURCES.txt"
echo "$images/SOURCES.txt"
