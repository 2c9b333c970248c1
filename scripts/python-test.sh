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
build/pyenv/bin/pip install -q --disable-pip-version-check "scikit-build-core>=0.10" "pybind11>=2.10" "numpy>=1.21" "pytest>=7" "fmpy==0.3.32" "h5py>=3.8" "pandas>=2.0"
# No build isolation: the build tools above are used, and build/wheel/ is reused between runs.
CMAKE_BUILD_PARALLEL_LEVEL=$(nproc) build/pyenv/bin/pip install -q --disable-pip-version-check --no-build-isolation .
JOINTSIM_CLI="$PWD/build/jointsim" build/pyenv/bin/python -m pytest -q -s tests/python "$@"
