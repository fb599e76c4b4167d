#!/bin/bash
# Per-vertex design cost (Theorem 2.2) of a base branch's builder against this checkout's, back to
# back per degree on one thread (CPU ms per vertex, nodes mean and max), so that the ratios come
# from one run on a shared machine. The base's library is built once into build/main-build with
# this checkout's native/benchmarks/design_benchmarks.cpp, so both print the same columns. With
# rounds > 1 the pairs repeat, interleaved, so that a slow spell of the machine hits both builders.
#
#   scripts/design_benchmark_vs_main.sh [base=main] [rays=1024] [degrees=4..9 as "4 5 6 7 8 9"]
#                                       [benchmark=design_benchmarks, or design_benchmarks_x86_64_v3]
#                                       [rounds=1]
set -euo pipefail
cd "$(dirname "$0")/.."
base=${1:-main}
rays=${2:-1024}
degrees=${3:-"4 5 6 7 8 9"}
benchmark=${4:-design_benchmarks}
rounds=${5:-1}
if ! [[ $rounds =~ ^[1-9][0-9]*$ ]]; then
  echo "rounds must be a positive integer, not '$rounds'" >&2
  exit 2
fi
# The base's build is reused only for the same commit and benchmark.
stamp="$(git rev-parse "$base") $benchmark"
if [ ! -x "build/main-build/native/$benchmark" ] || [ "$(cat build/main-build/stamp 2>/dev/null)" != "$stamp" ]; then
  rm -rf build/main-src build/main-build && mkdir -p build/main-src
  git archive "$base" | tar -x -C build/main-src
  cp native/benchmarks/design_benchmarks.cpp build/main-src/native/benchmarks/
  cmake -S build/main-src -B build/main-build -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 > /dev/null
  nice -n 10 cmake --build build/main-build -j2 --target "$benchmark" > /dev/null
  echo "$stamp" > build/main-build/stamp
fi
for round in $(seq "$rounds"); do
  [ "$rounds" -gt 1 ] && echo "round $round of $rounds"
  for d in $degrees; do
    echo "degree $d $base:   $(nice -n 10 "build/main-build/native/$benchmark" "$rays" "$d" 3 0 "$d" | grep -a -E "^ +$d \|")"
    echo "degree $d branch: $(nice -n 10 "build/native/$benchmark" "$rays" "$d" 3 0 "$d" | grep -a -E "^ +$d \|")"
  done
done
