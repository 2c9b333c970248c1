#!/usr/bin/env bash
# Quick start, command 2 (and CI): installs what is missing (with the test tools), builds everything, runs the whole
# C++ suite with CTest, then the Python package's tests (scripts/python-test.sh: builds the wheel with
# `pip install .` in build/pyenv). Every test writes only below a temporary folder of its own, so two checkouts may
# run this at the same time.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --test
scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)"
scripts/python-test.sh
