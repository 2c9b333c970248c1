#!/usr/bin/env bash
# Sanitizer build and test run (CI): the library, the CLI and the whole test suite built with clang and
# AddressSanitizer + UndefinedBehaviorSanitizer (every UB report fatal), instrumented for libFuzzer, in
# build-san/; then the suite under the sanitizers and every fuzz target for FUZZ_SECONDS (default 60) each.
# Any sanitizer report, crash, leak or fuzz failure fails the script.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --test
FUZZ_SECONDS="${FUZZ_SECONDS:-60}"
# File by file (no unity batches), so that a source file that misses an #include of its own still fails here.
CC=clang-14 CXX=clang++-14 cmake -S . -B build-san -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DJOINTSIM_FUZZ=ON -DJOINTSIM_BUILD_BENCHMARKS=OFF -DJOINTSIM_UNITY_BUILD=OFF >/dev/null
cmake --build build-san -j "$(nproc)"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Without the Slurm test (label slurm): it checks scheduling, resubmission and the daemons, which the gcc suite
# covers; under ASan its deliberately slow run (600 s simulated, about 7 s in the release build) outlasts its
# time limit. The CLI and batch code it drives are tested here by the CLI tests.
ctest --test-dir build-san --output-on-failure -j "$(nproc)" -LE slurm
if [ "$FUZZ_SECONDS" -gt 0 ]; then
  scripts/fuzz.sh build-san "$FUZZ_SECONDS"
fi
