#!/usr/bin/env bash
# Runs every libFuzzer target of tests/fuzz/targets.txt for SECONDS seconds each, starting from its seed
# corpus (the globs of targets.txt) and its past findings (tests/fuzz/regressions/NAME/). Fails on the first
# crash, sanitizer report, leak, timeout (an input running longer than 20 s) or out-of-memory.
#   scripts/fuzz.sh BUILD_DIR [SECONDS] [TARGET...]
# BUILD_DIR is a build configured with -DJOINTSIM_FUZZ=ON (scripts/sanitize.sh makes build-san/). The
# growing corpus of each target is kept in BUILD_DIR/fuzz-corpus/NAME/ (reused by the next run); a failing
# input is written to BUILD_DIR/fuzz-artifacts/NAME/ — copy it into tests/fuzz/regressions/NAME/ with the fix.
# Figures of each target (executions, coverage) are printed at the end.
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:?usage: scripts/fuzz.sh BUILD_DIR [SECONDS] [TARGET...]}"
seconds="${2:-60}"
shift $(( $# >= 2 ? 2 : 1 ))
only=("$@")
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
summary=()
while read -r name globs; do
  [[ -z "$name" || "$name" == \#* ]] && continue
  if [ ${#only[@]} -gt 0 ] && [[ ! " ${only[*]} " == *" $name "* ]]; then continue; fi
  exe="$build/tests/fuzz/fuzz_$name"
  [ -x "$exe" ] || { echo "fuzz.sh: $exe not built (configure $build with -DJOINTSIM_FUZZ=ON)" >&2; exit 2; }
  corpus="$build/fuzz-corpus/$name" artifacts="$build/fuzz-artifacts/$name"
  mkdir -p "$corpus" "$artifacts"
  # shellcheck disable=SC2086
  for f in $globs; do [ -f "$f" ] && cp "$f" "$corpus/seed_$(basename "$f")"; done
  regressions=()
  [ -d "tests/fuzz/regressions/$name" ] && regressions=("tests/fuzz/regressions/$name")
  log="$build/fuzz-artifacts/$name.log"
  echo "== fuzz_$name: ${seconds} s (log: $log)"
  status=0
  "$exe" "$corpus" "${regressions[@]}" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=4096 -max_len=16384 \
    -artifact_prefix="$artifacts/" -print_final_stats=1 >"$log" 2>&1 || status=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -1 || echo "cov: ?")
  if [ "$status" -ne 0 ]; then
    tail -n 60 "$log" >&2
    echo "fuzz.sh: fuzz_$name FAILED (exit $status); the input is in $artifacts/" >&2
    exit 1
  fi
  summary+=("fuzz_$name: $execs executions in ${seconds} s, $cov, no crash, leak or timeout")
done < tests/fuzz/targets.txt
printf '%s\n' "${summary[@]}"
