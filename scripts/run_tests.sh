#!/usr/bin/env bash
# Runs every test: installs what is missing, builds, then the C++ (GoogleTest), Python (pytest)
# and Blender (the add-on, headless) suites through CTest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j "$(nproc)"
