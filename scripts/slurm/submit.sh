#!/usr/bin/env bash
# Runs a tailsim sweep on a Slurm cluster: N array tasks (one shard each, scripts/slurm/sweep.sbatch)
# and a merge job that starts when all of them succeeded and writes OUT/merged, the folder one
# process would have written (measured wall times aside).
#   scripts/slurm/submit.sh EXPERIMENT.yaml OUT N [extra sbatch options, e.g. --partition=cpu]
# Prints the two job ids. OUT must be on a file system every node sees. Needs tailsim built
# (TAILSIM=path/to/tailsim, default: build/tailsim of this checkout).
set -euo pipefail
[ $# -ge 3 ] || { echo "usage: submit.sh EXPERIMENT.yaml OUT N [sbatch options]" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
exp=$(realpath "$1"); out=$(realpath -m "$2"); n=$3; shift 3
tailsim=$(realpath "${TAILSIM:-$here/../../build/tailsim}")
[ -x "$tailsim" ] || { echo "submit.sh: $tailsim is not executable (build tailsim or set TAILSIM)" >&2; exit 1; }
[[ "$n" =~ ^[1-9][0-9]*$ ]] || { echo "submit.sh: N must be a positive integer, got '$n'" >&2; exit 2; }
mkdir -p "$out/shards" "$out/logs"
array=$(sbatch --parsable --array=1-"$n" --chdir="$out/logs" --export=ALL,TAILSIM="$tailsim",EXP="$exp",OUT="$out" \
  "$@" "$here/sweep.sbatch")
array=${array%%;*}
shards=()
for k in $(seq 1 "$n"); do shards+=("$out/shards/$k-of-$n"); done
merge=$(sbatch --parsable --dependency=afterok:"$array" --job-name=tailsim-merge --chdir="$out/logs" \
  --output=merge-%j.out "$@" --wrap "$(printf '%q ' "$tailsim" merge "${shards[@]}" --out "$out/merged")")
merge=${merge%%;*}
echo "shards: job $array (array 1-$n), merge: job $merge -> $out/merged"
