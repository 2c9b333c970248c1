#!/usr/bin/env bash
# Quick start, command 1: install dependencies, build, run the default main job (the UR5 falling under
# gravity), which writes out/ur5_fall/ur5_fall.csv and prints the real-time factor.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
./build/jointsim run config/experiments/ur5_fall.yaml
