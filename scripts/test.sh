#!/usr/bin/env bash
# Quick start, command 2 (and CI): install what is missing, build, run the whole test suite with CTest, then the
# Python package's tests (scripts/python-test.sh: builds the wheel with `pip install .` in build/pyenv).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)"
scripts/python-test.sh
