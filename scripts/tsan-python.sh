#!/usr/bin/env bash
# The Python extension under ThreadSanitizer (CI): the library and jointsim._core built with gcc and
# -fsanitize=thread in build-tsan/, then the Python thread tests run against it with the TSan runtime preloaded
# into the (uninstrumented) interpreter. Python's GIL and our per-object locks are pthread mutexes, which TSan
# intercepts, so a data race between two threads inside the library (one Simulator used from two threads, or
# independent simulators sharing something they should not) is reported and fails the script.
#   scripts/tsan-python.sh [PYTEST -k EXPRESSION]
# Needs build/pyenv (scripts/python-test.sh makes it) for pytest, NumPy and pybind11.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --test
expr="${1:-thread}"
py=build/pyenv/bin/python
if [ ! -x "$py" ]; then
  echo "tsan-python.sh: $py missing: run scripts/python-test.sh first (it makes the virtual environment)" >&2
  exit 2
fi
flags="-fsanitize=thread -g -O1 -fno-omit-frame-pointer"
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DJOINTSIM_PYTHON=ON \
  -DJOINTSIM_BUILD_TESTS=OFF -DJOINTSIM_BUILD_BENCHMARKS=OFF -DJOINTSIM_BUILD_CLI=OFF \
  -DCMAKE_C_FLAGS="$flags" -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS=-fsanitize=thread \
  -DCMAKE_SHARED_LINKER_FLAGS=-fsanitize=thread -DCMAKE_MODULE_LINKER_FLAGS=-fsanitize=thread \
  -DPython_EXECUTABLE="$PWD/$py" -DPython3_EXECUTABLE="$PWD/$py" \
  -Dpybind11_DIR="$("$py" -m pybind11 --cmakedir)" >/dev/null
cmake --build build-tsan -j "$(nproc)" --target jointsim_python
# The package as the wheel lays it out: the Python sources, the extension and the shipped files (data/).
pkg=build-tsan/pkg/jointsim
rm -rf build-tsan/pkg && mkdir -p "$pkg"
cp python/jointsim/*.py python/jointsim/*.pyi python/jointsim/py.typed "$pkg/"
cp build-tsan/python/_core*.so "$pkg/"
ln -s "$PWD/config" "$pkg/data"
tsan_runtime="$(gcc -print-file-name=libtsan.so)"
base="$(mktemp -d "${TMPDIR:-/tmp}/jointsim-tsan.XXXXXX")"
trap 'rm -rf "$base"' EXIT
# halt_on_error: the first race fails the run. Reports from inside the interpreter itself (not instrumented) cannot
# occur: TSan checks instrumented accesses only.
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1 report_signal_unsafe=0 history_size=4" \
  LD_PRELOAD="$tsan_runtime" PYTHONPATH="$PWD/build-tsan/pkg" JOINTSIM_CLI="$PWD/build/jointsim" \
  "$py" -m pytest -q -p no:cacheprovider --basetemp="$base/pytest" tests/python/test_api.py -k "$expr"
echo "tsan-python.sh: no data race reported"
