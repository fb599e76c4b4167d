#!/usr/bin/env bash
# The main job on the built-in default scene. Until the Blender add-on lands, that job is the
# lobe designs: it builds them and prints the table (degree, nodes found by gradient projection,
# the lower bound, the Gauss product count, residuals, build times), and writes it to out/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install_dependencies.sh"
"$root/scripts/build.sh"
mkdir -p "$root/out"
"$root/build/native/lobe_design_table" 12 | tee "$root/out/lobe_designs.txt"
echo "Lobe design table written to $root/out/lobe_designs.txt"
