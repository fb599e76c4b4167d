#!/usr/bin/env python3
"""Builds the installable add-on zip: sd_lighting/ with the Python package, the GLSL shaders and
the native module sdnative (one build per CPython version and CPU level: --native may be given
several times).

    python3 scripts/package_addon.py --native build/native/addon/sdnative.cpython-311-x86_64-linux-gnu.so \
        [--native build/py313/native/addon/sdnative.cpython-313-x86_64-linux-gnu.so] --output build/sd_lighting.zip
    python3 scripts/package_addon.py --check build/sd_lighting.zip

Layout (one zip for both install paths: Preferences > Add-ons > Install on Blender 3.4 - 4.x via
bl_info, and Get Extensions > Install from Disk on 4.2+ via blender_manifest.toml):

    sd_lighting/__init__.py, *.py, the sub-packages' */*.py, blender_manifest.toml
    sd_lighting/shaders/*.glsl   (the shading, the world background, the equirect lookup they share)
    sd_lighting/sdnative.cpython-311-x86_64-linux-gnu.so   (Blender 3.4 - 5.0: CPython 3.11)
    sd_lighting/sdnative.cpython-313-x86_64-linux-gnu.so   (Blender 5.1+: CPython 3.13, if built)
    sd_lighting/sdnative_x86_64_v3.cpython-3XX-x86_64-linux-gnu.so   (the same for AVX2/FMA CPUs)
    sd_lighting/libembree3.so.3, libtbb.so.12   (what the modules load beyond SYSTEM_LIBRARIES)

The manifest's schema (1.0.0, Blender 4.2 - 5.0) has no python_versions key (Blender derives the
Python versions of an extension from its `wheels` only), so the manifest written into the zip
bounds the Blender versions instead: without a CPython 3.13 module it gets
blender_version_max = "5.1.0" (5.1 is the first Blender on 3.13), which the extension installer
honours. native.py picks the module of the running Python's ABI.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile
import zipfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
# The first Blender that no longer runs each CPython of the native modules (None: still current).
BLENDER_AFTER_PYTHON = {(3, 11): "5.1.0", (3, 13): None}

# What the zip's shared objects may load from the system: the libraries of the manylinux policies,
# at the symbol versions of manylinux_2_35 (glibc 2.35: Ubuntu 22.04, Fedora 36, Debian 12 and
# newer) and of GCC 11's libstdc++ (which Debian's Embree needs: GLIBCXX_3.4.29). Every other
# library a module loads (Embree, its TBB) is carried beside the modules, found through their
# RPATH $ORIGIN (native/CMakeLists.txt).
SYSTEM_LIBRARIES = {"linux-vdso.so.1", "ld-linux-x86-64.so.2", "libc.so.6", "libm.so.6", "libpthread.so.0",
                    "libdl.so.2", "librt.so.1", "libgcc_s.so.1", "libstdc++.so.6"}
NEWEST_SYMBOLS = {"GLIBC": (2, 35), "GLIBCXX": (3, 4, 29), "CXXABI": (1, 3, 13), "GCC": (7, 0, 0)}


def python_version(module_path):
    """(3, 11) for sdnative.cpython-311-x86_64-linux-gnu.so."""
    match = re.search(r"\.cpython-3(\d+)-", os.path.basename(module_path))
    if not match:
        sys.exit("package_addon: not a CPython extension module: %s" % module_path)
    return (3, int(match.group(1)))


def build(module_path):
    """The module's build, from its file name: "sdnative", or "sdnative_x86_64_v3" (native.py)."""
    return os.path.basename(module_path).split(".", 1)[0]


def carried_libraries(natives):
    """{soname: path} of the libraries the modules load that the system may lack (ldd: the
    libraries as this machine resolves them, those of the libraries included)."""
    carried = {}
    for native in natives:
        listing = subprocess.run(["ldd", native], capture_output=True, text=True, check=True).stdout
        for name, path in re.findall(r"^\s*(\S+) => (\S+)", listing, re.M):
            if path == "not":   # "=> not found"
                sys.exit("package_addon: %s needs %s, which this machine does not have" % (native, name))
            if name not in SYSTEM_LIBRARIES:
                carried[name] = os.path.realpath(path)
    return carried


def policy_violations(path, carried):
    """What the shared object `path` needs beyond the system libraries and the carried ones, and
    symbol versions newer than NEWEST_SYMBOLS (readelf): a list of lines, empty when it complies."""
    dynamic = subprocess.run(["readelf", "-d", "-W", path], capture_output=True, text=True, check=True).stdout
    needed = re.findall(r"\(NEEDED\).*\[(.+)\]", dynamic)
    problems = ["needs %s" % name for name in needed if name not in SYSTEM_LIBRARIES | set(carried)]
    versions = subprocess.run(["readelf", "-V", "-W", path], capture_output=True, text=True, check=True).stdout
    for family, version in set(re.findall(r"Name: (GLIBC|GLIBCXX|CXXABI|GCC)_([0-9.]+)", versions)):
        if tuple(int(x) for x in version.split(".")) > NEWEST_SYMBOLS[family]:
            problems.append("needs %s_%s" % (family, version))
    return sorted("%s: %s" % (os.path.basename(path), p) for p in problems)


def check_zip(zip_path):
    """The policy's violations of every shared object in the zip (their names and needs)."""
    with tempfile.TemporaryDirectory() as directory, zipfile.ZipFile(zip_path) as archive:
        objects = [n for n in archive.namelist() if re.search(r"\.so(\.\d+)*$", n)]
        for name in objects:
            archive.extract(name, directory)
        carried = {os.path.basename(n) for n in objects}
        return [line for name in objects for line in policy_violations(os.path.join(directory, name), carried)]


def manifest_text(path, natives):
    """The package's blender_manifest.toml, with blender_version_max from the newest Python
    among the native modules."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    newest = max(python_version(n) for n in natives)
    if newest not in BLENDER_AFTER_PYTHON:
        sys.exit("package_addon: no Blender range known for CPython %d.%d" % newest)
    maximum = BLENDER_AFTER_PYTHON[newest]
    if maximum and not re.search(r"^blender_version_max\s*=", text, re.M):
        line = ("# Written by scripts/package_addon.py: the native module is built for CPython %d.%d "
                "only,\n# and Blender %s moved to the next Python.\nblender_version_max = \"%s\"\n\n"
                % (newest + (maximum, maximum)))
        table = re.search(r"^\[", text, re.M)   # top-level keys go before the first [table]
        at = table.start() if table else len(text)
        text = text[:at] + line + text[at:]
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--native", action="append",
                        help="path of a built sdnative module (.so); once per CPython version and build")
    parser.add_argument("--output", help="zip to write")
    parser.add_argument("--check", metavar="ZIP",
                        help="only check the shared objects of a written zip against the policy (exit 1 if not)")
    args = parser.parse_args()
    if args.check:
        problems = check_zip(args.check)
        print("\n".join(problems) or "package_addon: %s: every shared object loads only the policy's "
                                        "system libraries and the ones it carries" % args.check)
        sys.exit(1 if problems else 0)
    if not args.native or not args.output:
        parser.error("--native and --output are required")

    package = os.path.join(ROOT, "addon", "sd_lighting")
    shaders = os.path.join(ROOT, "shaders")
    natives = [n for n in args.native if n]
    for native in natives:
        if not os.path.isfile(native):
            sys.exit("package_addon: native module not found: %s" % native)
    if len({(python_version(n), build(n)) for n in natives}) != len(natives):
        sys.exit("package_addon: two native modules of one build for the same CPython: %s" % ", ".join(natives))

    entries, texts = [], []
    for directory, subdirectories, names in os.walk(package):
        subdirectories[:] = sorted(d for d in subdirectories if d != "__pycache__")
        for name in sorted(names):
            if name.endswith(".py"):
                path = os.path.join(directory, name)
                entries.append((path, "sd_lighting/" + os.path.relpath(path, package).replace(os.sep, "/")))
    texts.append((manifest_text(os.path.join(package, "blender_manifest.toml"), natives),
                  "sd_lighting/blender_manifest.toml"))
    for name in sorted(os.listdir(shaders)):
        if name.endswith(".glsl"):
            entries.append((os.path.join(shaders, name), "sd_lighting/shaders/" + name))
    for native in natives:
        entries.append((native, "sd_lighting/" + os.path.basename(native)))
    carried = carried_libraries(natives)
    for soname, path in sorted(carried.items()):
        entries.append((path, "sd_lighting/" + soname))
    problems = [line for native in natives for line in policy_violations(native, carried)]
    problems += [line for path in carried.values() for line in policy_violations(path, carried)]
    if problems:
        sys.exit("package_addon: beyond the policy of the libraries a user's system has:\n  " + "\n  ".join(problems))

    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    temporary = args.output + ".tmp"
    with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
        for path, arcname in entries:
            archive.write(path, arcname)
        for text, arcname in texts:
            archive.writestr(arcname, text)
    os.replace(temporary, args.output)
    print("package_addon: wrote %s (%d files, %.1f MB; %s; carrying %s)" % (
        args.output, len(entries) + len(texts), os.path.getsize(args.output) / 1e6,
        ", ".join("%s for CPython %d.%d" % ((build(n),) + python_version(n)) for n in natives),
        ", ".join(sorted(carried)) or "no library"))


if __name__ == "__main__":
    main()
