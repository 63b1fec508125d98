#!/bin/sh
# Regenerates the models in mjcf/ from the generator (src/models/mujoco/mjcf_generator.cc):
#   tail_n<N>.xml                    the single-file model tailsim simulates (= a result folder's mjcf/<hash>.xml)
#   tailsim_n<N>.xml, scene_n<N>.xml the same robot in MuJoCo Menagerie form (mjcf/README.md)
# for the paper robot with an N = 1..6 link tail. Tests MujocoModel.MjcfFilesAreUpToDate and
# Menagerie.FilesInMjcfAreWhatTheGeneratorWrites fail until the files are regenerated after a change.
# Usage: scripts/mjcf_menagerie.sh [path/to/tailsim]   (default: build/tailsim)
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
tailsim=${1:-$root/build/tailsim}
for n in 1 2 3 4 5 6; do
  "$tailsim" mjcf --links "$n" --out "$root/mjcf/tail_n$n.xml" >/dev/null
  "$tailsim" mjcf --links "$n" --menagerie "$root/mjcf" >/dev/null
done
echo "regenerated $root/mjcf: tail_n1..6.xml, tailsim_n1..6.xml, scene_n1..6.xml"
