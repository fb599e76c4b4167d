#!/usr/bin/env bash
# The main job on the built-in default scene: installs what is missing, builds the native module
# and the add-on zip, then in Blender (headless) builds the scene — Suzanne on a ground plane
# under a Blender-shipped HDRI —, installs the add-on, bakes, renders the live shading to an
# image, saves the .blend, and prints where they are. Also writes the lobe-design table.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh"
mkdir -p "$root/out"
"$root/build/native/lobe_design_table" 8 > "$root/out/lobe_designs.txt"
echo "lobe designs:  $root/out/lobe_designs.txt"
/usr/bin/python3 "$root/blender_tests/run.py" --zip "$root/build/sd_lighting.zip" \
    --out "$root/build/blender_tests" --main-job "$root/out"
