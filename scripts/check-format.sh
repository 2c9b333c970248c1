#!/usr/bin/env bash
# Checks that every C++ source of the tree is formatted with the project's .clang-format (clang-format 14, Debian's
# clang-format-14; scripts/install-deps.sh --test installs it). Lists the files that are not and how to fix them;
# exit status 1 then, 77 when clang-format 14 is missing (CTest counts that as skipped). third_party/ is left as
# its authors wrote it. Run by CTest (format_check) and so by CI.
#   scripts/check-format.sh [SOURCE_DIR]      check
#   scripts/check-format.sh --fix             format the files in place
set -euo pipefail
fix=0
if [ "${1:-}" = "--fix" ]; then fix=1; shift; fi
src="${1:-$(dirname "$0")/..}"
cd "$src"
cf=$(command -v clang-format-14 || true)
if [ -z "$cf" ]; then
  echo "check-format: clang-format-14 not found (scripts/install-deps.sh --test installs it)" >&2
  exit 77
fi
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h' '*.cc' | grep -v '^third_party/')
else
  mapfile -t files < <(find . -path ./third_party -prune -o -path './build*' -prune -o \
                         \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' -o -name '*.cc' \) -print | sed 's|^\./||')
fi
if [ "$fix" -eq 1 ]; then
  "$cf" -i "${files[@]}"
  exit 0
fi
bad=()
for f in "${files[@]}"; do
  "$cf" --dry-run --Werror "$f" >/dev/null 2>&1 || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "check-format: ${#bad[@]} of ${#files[@]} files are not formatted with .clang-format:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix with: scripts/check-format.sh --fix (or clang-format-14 -i FILE)" >&2
  exit 1
fi
echo "check-format: ${#files[@]} files formatted"
