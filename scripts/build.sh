#!/usr/bin/env bash
# Configures and builds jointsim in build/ (Release, Ninja): everything, tests and benchmarks included (what the
# test command needs). Extra arguments go to `cmake --build` (e.g. --target jointsim_cli). JOINTSIM_WERROR=ON (set
# by .ci/run) turns compiler warnings into errors.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DJOINTSIM_BUILD_TESTS=ON -DJOINTSIM_BUILD_BENCHMARKS=ON \
      -DJOINTSIM_WERROR="${JOINTSIM_WERROR:-OFF}" >/dev/null
cmake --build build -j "$(nproc)" "$@"
