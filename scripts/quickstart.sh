#!/usr/bin/env bash
# Quick start, command 1: installs what building and running the CLI needs (no test tools), builds only the
# command-line tool `jointsim` (the library and the CLI: no tests, benchmarks or examples), and runs the main job:
# the UR5 digital twin following a 10 s excitation trajectory, which writes out/ur5_excitation/ur5_excitation.csv
# and summary.json and prints the real-time factor and what to look at next. The test command (scripts/test.sh)
# later adds the test tools and builds the rest in the same build/ folder.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
scripts/install-deps.sh
echo "jointsim: building the command-line tool in build/ ($(nproc) jobs)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DJOINTSIM_BUILD_TESTS=OFF -DJOINTSIM_BUILD_BENCHMARKS=OFF \
      >/dev/null
cmake --build build -j "$(nproc)" --target jointsim_cli
./build/jointsim run config/experiments/ur5_excitation.yaml
echo "jointsim: quick start done in $(( $(date +%s) - start )) s"
