#!/usr/bin/env bash
# Stress (CI, issue 26): the hostile-condition tests repeated, several at a time, each ending with a clear error or
# correct results and never a crash: two batches into one folder, data sets on a full (size-capped) file system, a
# resume over deleted logs (BatchSafety.*, tests/cli/test_batch_safety.cpp; the data-set writer's tests, Dataset.*),
# and one Python Simulator hammered from 4 threads (tests/python/test_api.py). Needs the build of scripts/test.sh.
#   scripts/stress.sh [REPEATS]   (default 5)
set -euo pipefail
cd "$(dirname "$0")/.."
repeats="${1:-5}"
ctest --test-dir build --output-on-failure -j 4 -R '^(BatchSafety|Dataset)\.' --repeat until-fail:"$repeats"
base="$(mktemp -d "${TMPDIR:-/tmp}/jointsim-stress.XXXXXX")"
trap 'rm -rf "$base"' EXIT
for k in $(seq "$repeats"); do
  JOINTSIM_CLI="$PWD/build/jointsim" build/pyenv/bin/python -m pytest -q -p no:cacheprovider \
    --basetemp="$base/run$k" tests/python/test_api.py -k "four_threads"
done
echo "stress.sh: $repeats rounds, no crash"
