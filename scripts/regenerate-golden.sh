#!/usr/bin/env bash
# Regenerates the golden reference logs tests/golden/<name>.csv from tests/golden/cases.txt (docs/regression.md):
# runs each case's experiment with its --set overrides and keeps the CSV header and every EVERY-th row.
# Usage: bash scripts/regenerate-golden.sh [JOINTSIM_EXECUTABLE] [CASE ...]
#   JOINTSIM_EXECUTABLE  default build/jointsim (relative to the current or the source directory, or absolute)
#   CASE ...             regenerate only these cases (default: all)
# Review the change with `jointsim compare OLD.csv NEW.csv` before committing regenerated references.
set -euo pipefail

src="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jointsim="${1:-build/jointsim}"
shift || true
# A relative path: from the current directory if it is there, else from the source directory.
case "$jointsim" in /*) ;; *) [ -x "$jointsim" ] && jointsim="$PWD/$jointsim" || jointsim="$src/$jointsim" ;; esac
[ -x "$jointsim" ] || { echo "regenerate-golden: no jointsim executable at $jointsim (build first)" >&2; exit 2; }

cases="$src/tests/golden/cases.txt"
work="$(mktemp -d "${TMPDIR:-/tmp}/jointsim_golden.XXXXXX")"
trap 'rm -rf "$work"' EXIT

count=0
while read -r name config every rtol atol overrides; do
  case "$name" in ''|'#'*) continue ;; esac
  if [ $# -gt 0 ]; then
    wanted=0
    for c in "$@"; do [ "$c" = "$name" ] && wanted=1; done
    [ $wanted = 1 ] || continue
  fi
  args=()
  for o in $overrides; do args+=(--set "$o"); done
  out="$work/$name"
  "$jointsim" run "$src/$config" -o "$out" "${args[@]}" >"$work/$name.log"
  log="$(awk '$1 == "log:" { print $2 }' "$work/$name.log")"
  [ -f "$log" ] || { echo "regenerate-golden: $name: no log found in the output of jointsim run" >&2; exit 1; }
  awk -v k="$every" 'NR == 1 || (NR - 2) % k == 0' "$log" >"$src/tests/golden/$name.csv.tmp"
  mv "$src/tests/golden/$name.csv.tmp" "$src/tests/golden/$name.csv"
  printf '%-24s %5d rows  %7d bytes  (rtol %s, atol %s)\n' "$name" \
    "$(($(wc -l <"$src/tests/golden/$name.csv") - 1))" "$(wc -c <"$src/tests/golden/$name.csv")" "$rtol" "$atol"
  count=$((count + 1))
done <"$cases"
if [ $# -gt 0 ] && [ "$count" -ne $# ]; then
  echo "regenerate-golden: regenerated $count of the $# named cases; names are the first field of $cases" >&2
  exit 2
fi
echo "regenerated $count golden logs in $src/tests/golden/ ($(du -sh "$src/tests/golden" | cut -f1) in all)"
