#!/usr/bin/env bash
# CTest docs_keys_current: the key tables in docs/experiment-format.md between the markers are
# exactly `tailsim schema --markdown` (generated from the settings declarations).
# Update: tests/docs_keys_test.sh SRC BUILD --update
set -euo pipefail
src=$1 build=$2 mode=${3:-check}
doc=$src/docs/experiment-format.md
begin='<!-- BEGIN generated: tailsim schema --markdown -->'
end='<!-- END generated -->'
gen=$(mktemp) new=$(mktemp)
trap 'rm -f "$gen" "$new"' EXIT
"$build/tailsim" schema --markdown > "$gen"
grep -qxF "$begin" "$doc" && grep -qxF "$end" "$doc" || { echo "markers missing in $doc"; exit 1; }
awk -v b="$begin" -v e="$end" -v g="$gen" '
  $0 == b { print; while ((getline l < g) > 0) print l; skip = 1; next }
  $0 == e { skip = 0 }
  !skip { print }' "$doc" > "$new"
if [ "$mode" = --update ]; then cp "$new" "$doc"; echo "updated $doc"; exit 0; fi
if ! diff -u "$doc" "$new"; then
  echo "docs/experiment-format.md differs from 'tailsim schema --markdown': run tests/docs_keys_test.sh $src $build --update"
  exit 1
fi
echo "docs/experiment-format.md key tables are current"
