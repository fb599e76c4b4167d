#!/usr/bin/env python3
"""Builds the installable add-on zip: sd_lighting/ with the Python package, the GLSL shaders and
the native module sdnative.

    python3 scripts/package_addon.py --native build/native/sdnative.cpython-311-x86_64-linux-gnu.so \
        --output build/sd_lighting.zip

Layout (one zip for both install paths: Preferences > Add-ons > Install on Blender 3.4 - 4.x via
bl_info, and Get Extensions > Install from Disk on 4.2+ via blender_manifest.toml):

    sd_lighting/__init__.py, *.py, utils/*.py, blender_manifest.toml
    sd_lighting/shaders/sd_shading_lib.glsl, sd_shading_vert.glsl, sd_shading_frag.glsl
    sd_lighting/sdnative.cpython-311-x86_64-linux-gnu.so
"""

import argparse
import os
import sys
import zipfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--native", required=True, help="path of the built sdnative module (.so)")
    parser.add_argument("--output", required=True, help="zip to write")
    args = parser.parse_args()

    package = os.path.join(ROOT, "addon", "sd_lighting")
    shaders = os.path.join(ROOT, "shaders")
    if not os.path.isfile(args.native):
        sys.exit("package_addon: native module not found: %s" % args.native)

    entries = []
    for directory, subdirectories, names in os.walk(package):
        subdirectories[:] = sorted(d for d in subdirectories if d != "__pycache__")
        for name in sorted(names):
            if name.endswith(".py") or name == "blender_manifest.toml":
                path = os.path.join(directory, name)
                entries.append((path, "sd_lighting/" + os.path.relpath(path, package).replace(os.sep, "/")))
    for name in sorted(os.listdir(shaders)):
        if name.endswith(".glsl"):
            entries.append((os.path.join(shaders, name), "sd_lighting/shaders/" + name))
    entries.append((args.native, "sd_lighting/" + os.path.basename(args.native)))

    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    temporary = args.output + ".tmp"
    with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
        for path, arcname in entries:
            archive.write(path, arcname)
    os.replace(temporary, args.output)
    print("package_addon: wrote %s (%d files)" % (args.output, len(entries)))


if __name__ == "__main__":
    main()
