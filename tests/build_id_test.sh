#!/usr/bin/env bash
# The build identity (kGitCommit, cmake/TailsimBuildId.cmake) is computed at build time: in a
# throw-away git repository holding a tiny project wired as CMakeLists.txt wires tailsim, an
# incremental build (no reconfigure) after a commit carries the new commit, after an uncommitted
# edit "<commit>-dirty-<hash of the diff>" (two different edits: two labels), and a build with
# nothing changed rewrites nothing (the header and the program keep their times).
# Usage: build_id_test.sh SOURCE_DIR
set -uo pipefail
SRC=$1
W=$(mktemp -d "${TMPDIR:-/tmp}/tailsim_buildid.XXXXXX")
trap 'rm -rf "$W"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
command -v git > /dev/null || { echo "SKIP: no git"; exit 0; }
R=$W/repo
mkdir -p "$R/cmake" && cp "$SRC/cmake/TailsimBuildId.cmake" "$SRC/cmake/tailsim_git_commit.cmake" "$R/cmake/"
cat > "$R/CMakeLists.txt" <<'CM'
cmake_minimum_required(VERSION 3.17)
project(buildid CXX)
include(cmake/TailsimBuildId.cmake)
tailsim_build_id(${PROJECT_BINARY_DIR}/generated/tailsim_git_commit.h)
add_executable(id main.cc)
target_include_directories(id PRIVATE ${PROJECT_BINARY_DIR}/generated)
add_dependencies(id tailsim_git_commit)
CM
cat > "$R/main.cc" <<'CC'
#include <cstdio>
#include "tailsim_git_commit.h"
int main() { std::puts(tailsim::kGitCommit); }
CC
echo one > "$R/notes.txt"
g() { git -C "$R" -c user.name=t -c user.email=t@t "$@"; }
g init -q && g add -A && g commit -qm one || fail "git"
cmake -S "$R" -B "$W/b" > /dev/null || fail "configure"
build() { cmake --build "$W/b" > "$W/log" 2>&1 || { cat "$W/log"; fail "build"; }; "$W/b/id"; }
want=$(g rev-parse --short=12 HEAD)
got=$(build); [ "$got" = "$want" ] || fail "first build: $got, want $want"
echo two > "$R/notes.txt" && g commit -qam two
want=$(g rev-parse --short=12 HEAD)
got=$(build); [ "$got" = "$want" ] || fail "incremental build after a commit: $got, want $want (the configure-time commit)"
echo "after a commit: $got"
echo three > "$R/notes.txt"
d1=$(build); [[ "$d1" == "$want-dirty-"* ]] || fail "build of an edited tree: $d1, want $want-dirty-<hash>"
echo four > "$R/notes.txt"
d2=$(build); [[ "$d2" == "$want-dirty-"* && "$d2" != "$d1" ]] || fail "two different edits share the label $d1 / $d2"
echo "edited: $d1, edited again: $d2"
t1=$(stat -c %y "$W/b/generated/tailsim_git_commit.h" "$W/b/id")
sleep 1.1
got=$(build); [ "$got" = "$d2" ] || fail "a build with nothing changed: $got, want $d2"
t2=$(stat -c %y "$W/b/generated/tailsim_git_commit.h" "$W/b/id")
[ "$t1" = "$t2" ] || fail "a build with nothing changed rewrote the header or relinked the program"
echo "nothing changed: nothing rebuilt"
