#!/usr/bin/env bash
# A tailsim sweep split into N shards run by GNU parallel (Debian package `parallel`), then merged:
# on this machine's cores, or on several hosts with a shared folder:
#   scripts/parallel_sweep.sh EXPERIMENT.yaml OUT N                 # N shards, as many at once as cores
#   PARALLEL_HOSTS=host1,host2 scripts/parallel_sweep.sh EXP OUT N  # parallel -S host1,host2 (ssh; same
#                                                                   # paths and tailsim build on each host)
# Writes OUT/shards/K-of-N and OUT/merged (the folder one process would have written, wall times aside).
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: parallel_sweep.sh EXPERIMENT.yaml OUT N" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
exp=$(realpath "$1"); out=$(realpath -m "$2"); n=$3
tailsim=$(realpath "${TAILSIM:-$here/../build/tailsim}")
command -v parallel >/dev/null || { echo "parallel_sweep.sh: GNU parallel not found (Debian: parallel)" >&2; exit 1; }
mkdir -p "$out/shards"
hosts=()
[ -n "${PARALLEL_HOSTS:-}" ] && hosts=(-S "$PARALLEL_HOSTS")
# One thread per shard: parallel runs one shard per core (or per host job slot).
parallel --will-cite --halt now,fail=1 "${hosts[@]}" \
  "$tailsim" run "$exp" --shard {}/"$n" --out "$out/shards/{}-of-$n" --threads 1 --quiet --no-render ::: $(seq 1 "$n")
shards=()
for k in $(seq 1 "$n"); do shards+=("$out/shards/$k-of-$n"); done
"$tailsim" merge "${shards[@]}" --out "$out/merged"
