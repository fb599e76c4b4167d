#!/usr/bin/env bash
# Configures and builds sd-lighting into build/ (Release), with Debian's Python, the one Blender uses
# (CPython 3.11: Debian's Blender 3.4 and Blender 4.2 - 5.0).
# When a CPython 3.13 is found (Blender 5.1+ runs 3.13: $SD_PYTHON313, python3.13 on PATH, or
# pyenv's), it also builds sdnative for it into build/py313 - with pybind11 2.13.6 from PyPI in a
# cached venv, Debian's pybind11 2.10 predating 3.13 - and the add-on zip carries both modules.
# Without one the zip carries only the 3.11 module and its manifest says blender_version_max 5.1.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

native313=""
py313="$(/usr/bin/python3 "$root/blender_tests/bpy_modules.py" find-python 3.13 || true)"
if [[ -n "$py313" ]]; then
  venv="${XDG_CACHE_HOME:-$HOME/.cache}/sd-lighting/py313-build"
  if ! "$venv/bin/python" -c 'import pybind11, sys; sys.exit(pybind11.__version__ != "2.13.6")' 2>/dev/null; then
    rm -rf "$venv"
    "$py313" -m venv "$venv" && "$venv/bin/python" -m pip install -q --disable-pip-version-check \
        pybind11==2.13.6 || rm -rf "$venv"
  fi
  if [[ -x "$venv/bin/python" ]]; then
    cmake -S "$root" -B "$root/build/py313" -DCMAKE_BUILD_TYPE=Release \
          -DPython3_EXECUTABLE="$venv/bin/python" -Dpybind11_DIR="$("$venv/bin/python" -m pybind11 --cmakedir)" \
          -DSD_BUILD_TESTS=OFF -DSD_BUILD_BENCHMARKS=OFF > /dev/null
    targets=(sdnative_addon)   # and the x86-64-v3 build where native/CMakeLists.txt defines one
    if cmake --build "$root/build/py313" --target help | grep sdnative_x86_64_v3 > /dev/null; then
      targets+=(sdnative_x86_64_v3)
    fi
    cmake --build "$root/build/py313" --target "${targets[@]}" -j "$(nproc)"
    native313="$(for target in "${targets[@]}"; do ls "$root"/build/py313/native/addon/"${target%_addon}".cpython-313-*.so; done |
                 paste -sd ';')"
  else
    echo "build.sh: pybind11 for CPython 3.13 could not be installed; building for 3.11 only" >&2
  fi
else
  echo "build.sh: no CPython 3.13 found; sdnative is built for 3.11 only (Blender 3.4 - 5.0)"
fi

cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 \
      -DSD_EXTRA_NATIVE_MODULES="$native313" > /dev/null
cmake --build "$root/build" -j "$(nproc)"
