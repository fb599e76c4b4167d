#!/usr/bin/env bash
# Installs the Debian packages sd-lighting builds, tests and runs with, when any is missing.
# Blender brings the HDRIs the tests light with; xvfb and Mesa's llvmpipe give it a GPU context
# without a display.
set -euo pipefail

packages=(cmake g++ make pkg-config libembree-dev pybind11-dev libglm-dev libopenimageio-dev
          libeigen3-dev python3-dev python3-numpy python3-pytest libgtest-dev libbenchmark-dev
          blender xvfb xauth libgl1-mesa-dri)

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if (( ${#missing[@]} )); then
  echo "Installing: ${missing[*]}"
  apt-get update
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}"
fi
