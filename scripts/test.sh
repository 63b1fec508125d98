#!/usr/bin/env bash
# README command 2: install what is missing, build Release, run every test (CTest + GoogleTest).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/tailsim run configs/default.yaml --out results/default
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@"
