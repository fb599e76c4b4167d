#!/usr/bin/env bash
# Runs every test: installs what is missing (Debian packages; the pinned Blender-as-a-module wheels
# in their cached venvs), builds, then the C++ (GoogleTest), Python (pytest) and Blender (the
# add-on, headless, on Debian's Blender 3.4.1 and on the bpy modules of
# blender_tests/bpy_versions.txt) suites through CTest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_dependencies.sh"
/usr/bin/python3 "$root/blender_tests/bpy_modules.py" install
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j "$(nproc)"
