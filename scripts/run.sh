#!/usr/bin/env bash
# README command 1: install what is missing, build Release, run the default experiment.
set -euo pipefail
cd "$(dirname "$0")/.."
TAILSIM_TARGET=tailsim scripts/setup.sh
build/tailsim run configs/default.yaml --out results/default "$@"
