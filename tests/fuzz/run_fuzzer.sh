#!/usr/bin/env bash
# Runs one fuzz target for a bounded time (the CTest tests fuzz_*, tests/CMakeLists.txt):
#   run_fuzzer.sh FUZZER SECONDS LEAKS_WHILE_FUZZING ARTIFACT_DIR SEED_DIR...
# 1. fuzzes for SECONDS from a fresh corpus and the seed directories (so every run starts from
#    the same inputs), -seed=1, 30 s per input, 4 GB RSS; LEAKS_WHILE_FUZZING 0 leaves the leak
#    check to step 2 (fuzz_environment_file: the only leak seen, inside OpenImageIO, is matched
#    to its library only by slow unwinding, which costs 10x the executions);
# 2. with LEAKS_WHILE_FUZZING 0, runs every input the run kept once more with the leak check on,
#    unwinding each allocation fully so that lsan_suppressions.txt can name the uninstrumented
#    library a leak is in.
# Any crash, sanitizer report, leak, broken contract or timeout fails (exit status != 0) and
# leaves the input in ARTIFACT_DIR.
set -euo pipefail
fuzzer="$1" seconds="$2" leaks="$3" artifacts="$4"
shift 4
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
corpus="$(mktemp -d)"
trap 'rm -rf "$corpus"' EXIT
mkdir -p "$artifacts"
export LSAN_OPTIONS="suppressions=$here/lsan_suppressions.txt:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1"
prefix="$artifacts/$(basename "$fuzzer")-"
# Without the leak check while fuzzing, ASan's own check at exit is off too (its stacks of
# OpenImageIO's allocations are cut short); step 2 checks every kept input.
ASAN_OPTIONS="detect_leaks=$leaks" "$fuzzer" -max_total_time="$seconds" -seed=1 -timeout=30 -rss_limit_mb=4096 -print_final_stats=1 \
          -detect_leaks="$leaks" -artifact_prefix="$prefix" "$corpus" "$@"
[[ "$leaks" == 0 ]] || exit 0
echo "run_fuzzer.sh: $(ls "$corpus" | wc -l) inputs kept; checking each for leaks"
ASAN_OPTIONS="fast_unwind_on_malloc=0" "$fuzzer" -runs=0 -timeout=30 -rss_limit_mb=4096 -detect_leaks=1 \
          -artifact_prefix="$prefix" "$corpus" "$@"
