#!/usr/bin/env bash
# CTest repository_stands_alone: the repository needs nothing outside itself.
#  - no tracked file refers to the old reading notes outside the repository, to the shared folder
#    beside it (dot-dot-slash shared) or to an absolute /work path (docs/paper-notes.md holds the
#    notes now);
#  - every relative Markdown link in a tracked *.md file points to a file or folder that exists
#    inside the repository, and no link is an absolute file path;
#  - every tracked file with a #! line is executable.
# Usage: check_repository.sh REPO_ROOT. Prints every problem as file:line: what; exit 1 if any.
set -uo pipefail
root=$(cd "${1:?usage: check_repository.sh REPO_ROOT}" && pwd -P) || exit 2
cd "$root" || exit 2

# Tracked files (a git checkout), or every file but build output (an unpacked archive).
if git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git -C "$root" ls-files)
else
  mapfile -t files < <(find . -type f -not -path './.git/*' -not -path './build*' -not -path './results/*' \
    -not -path './renders/*' | sed 's|^\./||' | sort)
fi
[ "${#files[@]}" -gt 0 ] || { echo "no files found under $root"; exit 2; }

problems=0
report() { echo "$1"; problems=$((problems + 1)); }

# Patterns assembled from pieces so this script does not match itself.
notes="READING""-NOTES"
shared='\.\./'"shared"
work='/'"work/"
existing=()
for f in "${files[@]}"; do [ -f "$f" ] && existing+=("$f"); done
while IFS= read -r hit; do  # file:line:text (-I skips binary files)
  f=${hit%%:*}
  rest=${hit#*:}
  report "$f:${rest%%:*}: refers outside the repository: ${rest#*:}"
done < <(grep -nIE -e "$notes" -e "$shared" -e "$work" -- "${existing[@]}")

# Relative Markdown links [text](target) outside fenced code blocks.
for f in "${files[@]}"; do
  case "$f" in *.md) ;; *) continue ;; esac
  [ -f "$f" ] || continue
  dir=$(dirname "$f")
  while IFS=$'\t' read -r line target; do
    target=${target%%#*}            # drop the anchor
    [ -n "$target" ] || continue    # a link to a heading of the same file
    case "$target" in
      [a-zA-Z]*:*) continue ;;      # http:, https:, mailto:, ...
      /*) report "$f:$line: link to an absolute path: $target"; continue ;;
    esac
    resolved=$(realpath -m "$dir/$target")
    case "$resolved/" in
      "$root"/*) ;;
      *) report "$f:$line: link leaves the repository: $target"; continue ;;
    esac
    [ -e "$resolved" ] || report "$f:$line: link to a missing file: $target"
  done < <(awk '/^[ \t]*```/ { fence = !fence; next }
                !fence {
                  s = $0
                  while (match(s, /\]\([^) \t]+/)) {
                    printf "%d\t%s\n", NR, substr(s, RSTART + 2, RLENGTH - 2)
                    s = substr(s, RSTART + RLENGTH)
                  }
                }' "$f")
done

# Reports and plots read result folders, never YAML inputs: no yaml-cpp in src/plotting
# or src/app, and the CMake plotting target does not name it.
while IFS= read -r hit; do
  report "$hit: the plotting and app layers read result folders through the experiments layer, not YAML"
done < <(grep -rnE 'yaml-cpp|YAML::' "$root/src/plotting" "$root/src/app" 2>/dev/null || true)
grep -qE '^tailsim_layer\(tailsim_plotting [^)]*yaml' "$root/CMakeLists.txt" &&
  report "CMakeLists.txt: tailsim_plotting links yaml-cpp"

# Every script with a #! line can be run the way the docs write it (scripts/bench_scale.sh ...):
# executable in a checkout (git's mode 100755) or, unpacked, on disk.
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  head -c 2 -- "$f" | grep -q '^#!' || continue
  if git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    mode=$(git -C "$root" ls-files -s -- "$f" | cut -d' ' -f1)
    [ "$mode" = 100755 ] || report "$f: has a #! line but is not executable (git mode $mode: git update-index --chmod=+x)"
  else
    [ -x "$f" ] || report "$f: has a #! line but is not executable"
  fi
done

if [ "$problems" -gt 0 ]; then
  echo "$problems problem(s): the repository must stand alone (reading notes: docs/paper-notes.md)"
  exit 1
fi
echo "ok: ${#files[@]} files checked, nothing refers outside the repository, every Markdown link resolves"
