#!/usr/bin/env bash
# README command 1: install what is missing, build Release, run the default experiment.
set -euo pipefail
cd "$(dirname "$0")/.."
TAILSIM_TARGET=tailsim scripts/setup.sh
build/tailsim run configs/default.yaml --out "$PWD/results/default" --fresh "$@"  # absolute: the line it prints names the folder wherever the user stands; --fresh: a rebuilt tailsim runs it again (the folder is this script's)
