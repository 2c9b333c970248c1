#!/usr/bin/env bash
# The Python package's tests (run by scripts/test.sh after the C++ suite): a virtual environment in
# build/pyenv (Debian's Python refuses system-wide pip installs) with the build tools from PyPI, the wheel built
# from the repository root by scikit-build-core (`pip install .`, its CMake build kept in build/wheel/ so a
# second run only recompiles what changed), then pytest on tests/python against the CLI in build/.
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PYTHON:-python3}
if [ ! -x build/pyenv/bin/python ]; then
  "$PY" -m venv build/pyenv
fi
build/pyenv/bin/pip install -q --disable-pip-version-check "scikit-build-core>=0.10" "pybind11>=2.10" "numpy>=1.21" "pytest>=7" "fmpy==0.3.32" "h5py>=3.8" "pandas>=2.0" "hypothesis>=6.100" "selenium>=4.10"
# No build isolation: the build tools above are used, and build/wheel/ is reused between runs.
# JOINTSIM_WERROR=ON (set by .ci/run): compiler warnings of the extension are errors too.
CMAKE_BUILD_PARALLEL_LEVEL=$(nproc) build/pyenv/bin/pip install -q --disable-pip-version-check --no-build-isolation \
  --config-settings=cmake.define.JOINTSIM_WERROR="${JOINTSIM_WERROR:-OFF}" .
# pytest's temporary folders below one of this run's own (two checkouts may test at the same time).
base=$(mktemp -d "${TMPDIR:-/tmp}/jointsim_pytest.XXXXXX")
status=0
# Screenshots of the viewer's browser tests (tests/python/test_view_browser.py) are kept, in a folder of this run's own.
mkdir -p build/test-artefacts
artefacts=$(mktemp -d "$PWD/build/test-artefacts/pytest.XXXXXX")
JOINTSIM_ARTEFACT_DIR="$artefacts" JOINTSIM_CLI="$PWD/build/jointsim" build/pyenv/bin/python -m pytest -q -s --basetemp="$base/t" tests/python "$@" || status=$?
[ "$status" -eq 0 ] && rm -rf "$base" || echo "jointsim: pytest's temporary folders kept in $base" >&2
ls "$artefacts"/*.png >/dev/null 2>&1 && echo "jointsim: the browser tests' screenshots are in $artefacts"
exit "$status"
