#!/usr/bin/env bash
# README command 2: install what is missing, build Release, run every test (CTest + GoogleTest).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build/tailsim run configs/default.yaml --out "$PWD/results/default" --fresh
# Every test cleans up after itself: they run with a fresh TMPDIR, and anything left in it fails
# the run (tests/scratch_dir.h is the tests' scratch folder).
scratch="$(mktemp -d "${TMPDIR:-/tmp}/tailsim-tests.XXXXXX")"
status=0
TMPDIR="$scratch" ctest --test-dir build --output-on-failure -j"$(nproc)" "$@" || status=$?
left="$(find "$scratch" -mindepth 1 -maxdepth 1 -printf '%f\n' | head -20)"
if [ -n "$left" ]; then
  echo "tests left files in TMPDIR ($scratch):" >&2
  echo "$left" >&2
  [ "$status" -ne 0 ] || status=1
fi
rm -rf "$scratch"
exit "$status"
