#!/usr/bin/env bash
# Runs blender_tests/test_portable.py on a bpy module in a mount namespace where Debian's Embree, TBB
# and OpenImageIO (and every library file named after them) read as empty: the zip must bake with the
# libraries it carries (issue 31). Needs root (unshare -m); exits 77 (skipped) without it.
#   blender_tests/hidden_libraries.sh BPY_VERSION ZIP OUT
set -euo pipefail
version="$1" zip="$2" out="$3"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ "$(id -u)" != 0 ]] || ! unshare -m true 2>/dev/null; then
  echo "hidden_libraries.sh: needs root and mount namespaces (unshare -m); skipped"
  exit 77
fi
hidden="$(for f in /usr/lib/x86_64-linux-gnu/lib{embree3,tbb,tbbmalloc,OpenImageIO,OpenImageIO_Util}.so.*; do
            if [[ -e "$f" ]]; then readlink -f "$f"; fi; done | sort -u | paste -sd:)"
export SD_HIDDEN_LIBRARIES="$hidden"
exec unshare -m bash -c '
  IFS=: read -ra files <<< "$SD_HIDDEN_LIBRARIES"
  for f in "${files[@]}"; do mount --bind /dev/null "$f"; done
  exec /usr/bin/python3 "$0"/blender_tests/run.py --bpy "$1" --zip "$2" --out "$3" test_portable' \
  "$root" "$version" "$zip" "$out"
