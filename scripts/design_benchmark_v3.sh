#!/bin/bash
# Per-vertex design cost (Theorem 2.2) of the portable library against its x86-64-v3 build
# (native/CMakeLists.txt), back to back per degree on one thread (CPU ms per vertex, nodes mean and
# max), so that the ratios come from one run on a shared machine. Needs a built build/.
#
#   scripts/design_benchmark_v3.sh [rays=1024] [degrees="4 5 6 7 8 9"] [max_cold_degree=0]
set -euo pipefail
cd "$(dirname "$0")/.."
rays=${1:-1024}
degrees=${2:-"4 5 6 7 8 9"}
cold=${3:-0}
for d in $degrees; do
  for build in design_benchmarks design_benchmarks_x86_64_v3; do
    printf "%-28s %s\n" "$build" "$(build/native/$build "$rays" "$d" 3 "$cold" "$d" | grep -a -E "^ +$d \|")"
  done
done
