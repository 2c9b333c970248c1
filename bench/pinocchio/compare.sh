#!/usr/bin/env bash
# jointsim's rigid-body benchmarks against Pinocchio 4.1 on the same UR5 and the same 64 random states, in one run.
# Pinocchio comes from PyPI (the `pin` wheel, in a scratch virtual environment; its headers are compiled here with
# -O3 -march=native, header-only: the wheel's compiled library uses another Eigen alignment than a -march=native
# translation unit). Needs ./build (the README build). Usage: bash bench/pinocchio/compare.sh [scratch-dir]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${1:-$root/build/pinocchio-compare}
mkdir -p "$work"
if [ ! -x "$work/venv/bin/python" ]; then
  python3 -m venv "$work/venv"
  "$work/venv/bin/pip" install --quiet "pin==4.1.0"
fi
prefix=$("$work/venv/bin/python" -c 'import cmeel, sys; print(cmeel.__path__[0] + ".prefix")' 2>/dev/null ||
         ls -d "$work"/venv/lib/python3*/site-packages/cmeel.prefix)
libs=$(sed -n 's/^ *LINK_LIBRARIES = //p' <(grep -A4 '^build bench/bench_multibody:' "$root/build/build.ninja") | head -1)
g++ -O2 -std=c++17 -I"$root/include" -I/usr/include/eigen3 "$root/bench/pinocchio/dump_ur5.cpp" -o "$work/dump_ur5" \
  $(echo "$libs" | sed "s#src/libjointsim.a#$root/build/src/libjointsim.a#; s#-lbenchmark##; s#/usr/lib/x86_64-linux-gnu/libbenchmark[^ ]*##g") -lgomp
"$work/dump_ur5" "$root/config/robots/ur5.yaml" > "$work/ur5.txt"
[ -x "$work/pin_ur5" ] || g++ -O3 -march=native -DNDEBUG -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_MPL_LIMIT_LIST_SIZE=30 \
  -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 -DBOOST_FUSION_INVOKE_MAX_ARITY=12 -std=c++17 -I"$prefix/include" -I/usr/include/eigen3 \
  "$root/bench/pinocchio/pin_ur5.cpp" -o "$work/pin_ur5" -lbenchmark -lpthread
for i in 1 2; do
  "$root/build/bench/bench_multibody" --benchmark_min_time=1 --benchmark_filter='RNEA|CRBA$|ABA' 2>/dev/null | grep UR5
  UR5_TXT="$work/ur5.txt" "$work/pin_ur5" --benchmark_min_time=1 2>/dev/null | grep PIN
done
