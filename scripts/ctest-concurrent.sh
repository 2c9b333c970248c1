#!/usr/bin/env bash
# Runs the C++ suite of build/ COPIES times at once, each with PARALLEL tests at a time (defaults 2 and 8): what two
# checkouts testing on one machine, or a developer's second run, do to each other's files. Every test writes only
# below a temporary folder of its own (tests/test_util.hpp TempDir; checked when building), so all runs must pass.
# Run by .ci/run after the test command.
#   scripts/ctest-concurrent.sh [COPIES] [PARALLEL] [extra ctest arguments]
set -euo pipefail
cd "$(dirname "$0")/.."
copies="${1:-2}"
parallel="${2:-8}"
shift $(( $# > 2 ? 2 : $# ))
logs=$(mktemp -d "${TMPDIR:-/tmp}/jointsim_ctest_concurrent.XXXXXX")
pids=()
start=$(date +%s)
for i in $(seq 1 "$copies"); do
  ctest --test-dir build --output-on-failure -j "$parallel" "$@" >"$logs/run$i.log" 2>&1 &
  pids+=($!)
done
failed=0
for i in $(seq 1 "$copies"); do
  if wait "${pids[$((i - 1))]}"; then
    echo "ctest run $i of $copies at once (-j $parallel): $(grep -E 'tests passed|tests failed' "$logs/run$i.log")"
  else
    failed=1
    echo "ctest run $i of $copies at once (-j $parallel) FAILED:" >&2
    grep -E "\*\*\*Failed|\*\*\*Timeout|Exception|tests failed|^\s+[0-9]+ - " "$logs/run$i.log" >&2 || true
  fi
done
echo "ctest-concurrent: $copies runs in $(( $(date +%s) - start )) s"
if [ "$failed" -ne 0 ]; then
  echo "ctest-concurrent: logs kept in $logs" >&2
  exit 1
fi
rm -rf "$logs"
