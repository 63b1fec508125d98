#!/usr/bin/env bash
# Builds tailsim and its tests with AddressSanitizer + UndefinedBehaviorSanitizer (GCC) in
# build-asan/ and runs CTest there; any sanitizer report fails the test that raised it
# (halt_on_error). LeakSanitizer suppressions: scripts/lsan-suppressions.txt (only OSMesa's,
# LLVM's and libhdf5's own allocations, never tailsim's).
#   scripts/sanitize.sh              every test but the slowest end-to-end one (see EXCLUDE)
#   scripts/sanitize.sh -R loader    extra arguments go to ctest
# .ci/run calls it after the normal tests when CI=true.
set -euo pipefail
cd "$(dirname "$0")/.."
launcher=()
if command -v ccache >/dev/null; then
  export CCACHE_BASEDIR="$PWD/.."
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
# EIGEN_MALLOC_ALREADY_ALIGNED=1: under ASan, Eigen switches to its own offset ("handmade") aligned
# malloc unless told otherwise, while libpagmo (built without ASan) frees Eigen vectors with plain
# free(); pagmo's CMA-ES copies its Eigen members across that boundary, so ASan reports a bad free
# that a normal build never has. glibc's malloc is 16-byte aligned on x86-64, which is all Eigen
# asks for without AVX, so this keeps both sides on malloc/free as in the Release build.
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
# Warnings are errors in the Release build (scripts/setup.sh under CI); not here: GCC's sanitizer
# instrumentation raises false -Wmaybe-uninitialized / -Wstringop-* warnings in library headers.
WERROR=OFF
# No Python module here: an ASan-instrumented extension cannot be loaded into the (uninstrumented)
# python3 interpreter without preloading libasan; the Release suite runs the Python tests.
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" -DTAILSIM_WERROR=$WERROR -DTAILSIM_BENCHMARKS=OFF \
  -DTAILSIM_BUILD_PYTHON=OFF "${launcher[@]}" >/dev/null
cmake --build build-asan -j"$(nproc)"
export ASAN_OPTIONS="halt_on_error=1:abort_on_error=1:detect_leaks=1:detect_stack_use_after_return=1:strict_string_checks=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan-suppressions.txt:print_suppressions=0"
# readme_tour runs the paper suite three times (about 2 min in Release, over 15 min under ASan);
# the same code paths run in the cli test and the GoogleTest suites, which do run here.
# readme_images_current compares hashes of the Release build's output bit for bit; this build is
# -O2, so its last digits may differ without anything being wrong.
# downstream_cmake installs this build's (instrumented) libraries into a plain downstream build: it
# is a packaging test, run by the Release suite.
# shard_merge and slurm_sweep run the paper suite several times (minutes under ASan); their code
# (sharding, merge) is plain file handling around the runner that the cli and runner tests cover.
EXCLUDE='^(readme_tour|readme_images_current|downstream_cmake|shard_merge|slurm_sweep)$'
ctest --test-dir build-asan --output-on-failure -j"$(nproc)" -E "$EXCLUDE" "$@"
