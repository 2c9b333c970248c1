#!/usr/bin/env bash
# Quick start, command 1: install dependencies, build, and run the main job: the UR5 digital twin
# following a 10 s excitation trajectory, which writes out/ur5_excitation/ur5_excitation.csv and
# summary.json and prints the real-time factor.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
./build/jointsim run config/experiments/ur5_excitation.yaml
