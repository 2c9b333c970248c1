#!/usr/bin/env bash
# Installs the Debian 12 packages jointsim needs (idempotent; silent when everything is there). Run as root, or with
# sudo available. See third_party_notes.md for what each package is for.
#   scripts/install-deps.sh           what building the library and running the CLI needs (the quick start)
#   scripts/install-deps.sh --test    that, plus what the test command and CI need: GoogleTest, Google Benchmark,
#                                     clang 14 with the sanitizer runtimes and clang-format, Slurm and MUNGE,
#                                     Python's venv and headers, headless Chromium and its WebDriver (the viewer's
#                                     browser tests)
# The viewer (`jointsim view`) embeds three.js (Debian libjs-three) and uPlot, which Debian does not package: it comes
# from the npm registry (npm install -g uplot@UPLOT_VERSION; Debian's npm when no npm is on PATH).
set -euo pipefail
PACKAGES=(cmake ninja-build g++ pkg-config
          libeigen3-dev libsundials-dev liburdfdom-dev libtinyxml-dev libyaml-cpp-dev libcli11-dev libceres-dev
          nlohmann-json3-dev libxxhash-dev libzip-dev libhdf5-dev gnuplot-nox libjs-three)
UPLOT_VERSION=1.6.32
TEST_PACKAGES=(libgtest-dev libgmock-dev libbenchmark-dev
               clang-14 libclang-rt-14-dev libomp-14-dev clang-format-14
               slurm-wlm munge iproute2
               python3 python3-venv python3-dev
               chromium chromium-driver)
case "${1:-}" in
  "") ;;
  --test) PACKAGES+=("${TEST_PACKAGES[@]}") ;;
  *) echo "usage: scripts/install-deps.sh [--test]" >&2; exit 2 ;;
esac
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
command -v npm >/dev/null 2>&1 || missing+=(npm)
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
install_uplot() {
  local root
  root=$(npm root -g)
  if [ "$(node -p "try { require('$root/uplot/package.json').version } catch (e) { '' }" 2>/dev/null)" != "$UPLOT_VERSION" ]; then
    echo "jointsim: installing uplot@$UPLOT_VERSION from the npm registry"
    $SUDO npm install -g --no-audit --no-fund --loglevel=error "uplot@$UPLOT_VERSION" >/dev/null
  fi
}
if [ ${#missing[@]} -eq 0 ]; then
  install_uplot
  exit 0
fi
echo "jointsim: installing Debian packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
# apt's own chatter (and harmless maintainer-script notes such as "no alternatives for petsc", from a dependency of
# libsundials-dev) goes to a log that is shown only when apt fails.
log=$(mktemp "${TMPDIR:-/tmp}/jointsim_apt.XXXXXX")
if ! { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"; } >"$log" 2>&1; then
  cat "$log" >&2
  echo "jointsim: apt-get failed (log above; kept in $log)" >&2
  exit 1
fi
rm -f "$log"
install_uplot
