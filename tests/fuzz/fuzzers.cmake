# The libFuzzer targets, each tests/fuzz/<name>.cpp: listed once for the fuzzer build
# (tests/fuzz/CMakeLists.txt) and for the CTest tests that run them (tests/CMakeLists.txt).
set(SD_FUZZERS fuzz_environment_file fuzz_environment_pixels fuzz_visibility_bake fuzz_reference
    fuzz_weighted_design fuzz_shading)
# Seconds each target runs in the test command (longer by hand: README, Testing).
set(SD_FUZZ_SECONDS 10)
