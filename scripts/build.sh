#!/usr/bin/env bash
# Configures and builds sd-lighting into build/ (Release), with Debian's Python, the one Blender uses.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 > /dev/null
cmake --build "$root/build" -j "$(nproc)"
