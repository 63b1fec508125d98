# Writes the build's git identity into a header, at build time (cmake -P, run by the custom target
# tailsim_git_commit on every build, see cmake/TailsimBuildId.cmake):
#   cmake -DSOURCE_DIR=<checkout> -DOUT=<header> -P tailsim_git_commit.cmake
# The identity is `git describe --always --dirty --abbrev=12 --exclude=*` (the commit's 12 hex digits,
# "-dirty" when tracked files differ from it), and for a dirty tree the first 12 hex digits of the
# SHA-256 of `git diff HEAD`, so two different uncommitted trees never share one label. "" outside a
# git checkout. The header is rewritten only when the identity changed: nothing rebuilds needlessly.
set(_id "")
find_program(_git git)
if(_git)
  execute_process(COMMAND ${_git} describe --always --dirty --abbrev=12 --exclude=*
                  WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE _id OUTPUT_STRIP_TRAILING_WHITESPACE
                  RESULT_VARIABLE _rc ERROR_QUIET)
  if(NOT _rc EQUAL 0)
    set(_id "")
  elseif(_id MATCHES "-dirty$")
    execute_process(COMMAND ${_git} diff HEAD WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE _diff ERROR_QUIET)
    string(SHA256 _h "${_diff}")
    string(SUBSTRING "${_h}" 0 12 _h)
    set(_id "${_id}-${_h}")
  endif()
endif()
set(_text "// Generated at build time by cmake/tailsim_git_commit.cmake. Do not edit.
#pragma once

namespace tailsim {
// The source tree this binary was built from: `git describe --always --dirty --abbrev=12` (plus a
// hash of the uncommitted changes when dirty) at build time; \"\" outside a git checkout.
inline constexpr const char* kGitCommit = \"${_id}\";
}  // namespace tailsim
")
set(_old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" _old)
endif()
if(NOT _old STREQUAL _text)
  file(WRITE "${OUT}" "${_text}")
endif()
