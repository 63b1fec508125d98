#!/usr/bin/env bash
# README command 2: install what is missing, build Release, run every test (CTest + GoogleTest).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/tailsim run configs/default.yaml --out "$PWD/results/default" --fresh
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@"
