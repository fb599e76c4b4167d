#!/usr/bin/env bash
# Installs the Debian packages sd-lighting builds, tests and runs with, when any is missing.
# Blender brings the HDRIs the tests light with; xvfb and Mesa's llvmpipe give it a GPU context
# without a display. python3-venv makes the venvs of Blender as a Python module (the bpy wheels,
# blender_tests/bpy_modules.py); python3-pip builds the module's wheel (scripts/build.sh); the libraries after it are the system libraries those wheels load
# (OpenGL/EGL through libglvnd and Mesa, X11 client libraries, OpenMP). mesa-vulkan-drivers: Mesa's
# lavapipe, the Vulkan driver on which Blender 5.3 (whose default backend is Vulkan; without a
# driver it falls back to OpenGL) runs the GPU tests. glslang-tools: the strict GLSL checks of
# every shader variant (blender_tests/test_shader_variants.py). clang and libclang-rt-14-dev
# (libFuzzer and the sanitizers' runtimes for clang 14): the fuzz targets (tests/fuzz); ccache
# keeps their sanitizer build between clean clones.
# assimp-testmodels (a real asset with hard edges) and python3-matplotlib (its plots): the
# accuracy-cost report (blender_tests/accuracy_report.py).
set -euo pipefail

packages=(cmake g++ make pkg-config libembree-dev pybind11-dev libglm-dev libopenimageio-dev
          libeigen3-dev python3-dev python3-numpy python3-pytest libgtest-dev libbenchmark-dev
          blender xvfb xauth libgl1-mesa-dri
          python3-venv python3-pip libegl1 libgl1 libegl-mesa0 libx11-6 libxext6 libxfixes3 libxi6 libxrender1
          libxxf86vm1 libxkbcommon0 libsm6 libice6 libgomp1 mesa-vulkan-drivers
          glslang-tools clang libclang-rt-14-dev ccache assimp-testmodels python3-matplotlib)

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if (( ${#missing[@]} )); then
  echo "Installing: ${missing[*]}"
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
fi
