#!/usr/bin/env bash
# Fuzzes the loaders of every input file and the Python keyword path (tests/fuzz_experiment_loader.cc)
# with libFuzzer, ASan and UBSan:
# builds it with clang in build-fuzz/ (CMake option TAILSIM_FUZZ) and runs the CTest test
# fuzz_experiment_loader, which starts from the seed corpus configs/ and keeps what it finds in
# build-fuzz/fuzz-corpus/ (so each run continues the last). Crashing inputs: build-fuzz/fuzz-artifacts/.
#   scripts/fuzz.sh           60 s (what CI runs)
#   scripts/fuzz.sh 1800      a longer local run (30 min: ~10^6 executions on one core)
# Reproduce a finding: build-fuzz/tests/fuzz_experiment_loader build-fuzz/fuzz-artifacts/crash-...
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-60}
launcher=()
if command -v ccache >/dev/null; then
  export CCACHE_BASEDIR="$PWD/.."
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DTAILSIM_FUZZ=ON \
  -DTAILSIM_FUZZ_SECONDS="$secs" "${launcher[@]}" >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target fuzz_experiment_loader
status=0
ctest --test-dir build-fuzz --output-on-failure || status=$?
log=build-fuzz/Testing/Temporary/LastTest.log
echo "fuzz_experiment_loader, ${secs} s:"
grep -E '^(Done [0-9]+ runs|stat::number_of_executed_units|stat::peak_rss_mb|stat::new_units_added)' "$log" || true
echo "corpus: $(find build-fuzz/fuzz-corpus -type f | wc -l) inputs in build-fuzz/fuzz-corpus" \
     "(+ $(find configs -type f | wc -l) seeds in configs/)"
echo "crashes/timeouts/leaks/ooms: $(find build-fuzz/fuzz-artifacts -type f \( -name 'crash-*' -o -name 'timeout-*' \
  -o -name 'leak-*' -o -name 'oom-*' \) | wc -l) in build-fuzz/fuzz-artifacts" \
  "(slow units, only reported: $(find build-fuzz/fuzz-artifacts -type f -name 'slow-unit-*' | wc -l))"
exit $status
