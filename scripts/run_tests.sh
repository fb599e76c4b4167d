#!/usr/bin/env bash
# Runs the tests: installs what is missing (Debian packages; the pinned Blender-as-a-module wheels
# in their cached venvs), builds, then the C++ (GoogleTest), Python (pytest) and Blender (the
# add-on, headless, on Debian's Blender 3.4.1 and on the bpy modules of
# blender_tests/bpy_versions.txt) suites through CTest, in one of two tiers (tests/CMakeLists.txt):
#   scripts/run_tests.sh           the full tier, every test (what .ci/run runs)
#   scripts/run_tests.sh --quick   the quick tier, under 5 minutes, for every change
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
tier=(-LE quick_only)
case "${1:-}" in
  "") ;;
  --quick) tier=(-L quick) ;;
  *) echo "usage: scripts/run_tests.sh [--quick]" >&2; exit 2 ;;
esac
"$root/scripts/install_dependencies.sh"
/usr/bin/python3 "$root/blender_tests/bpy_modules.py" install
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j "$(nproc)" "${tier[@]}"
