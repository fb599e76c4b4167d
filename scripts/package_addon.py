#!/usr/bin/env python3
"""Builds the add-on's two zips from its repaired wheels (scripts/build.sh; pyproject.toml): the
Python package, the GLSL shaders and the native module sdnative (one wheel per CPython).

    python3 scripts/package_addon.py --wheels build/wheels --output build/sd_lighting.zip \
        --extension-output build/sd_lighting_extension.zip
    python3 scripts/package_addon.py --check build/sd_lighting.zip build/sd_lighting_extension.zip
    python3 scripts/package_addon.py --wheel-policy AUDITWHEEL build/wheels/*.whl

Layout:

    both:  sd_lighting/__init__.py, *.py, the sub-packages' */*.py
           sd_lighting/shaders/*.glsl   (the shading, the world background, the equirect lookup they share)
    sd_lighting.zip, the legacy add-on (Preferences > Add-ons > Install: Blender 3.4 - 4.1, and
    4.2+'s "Install legacy Add-on"): the wheels' files, as pip would install them, in the package
           sd_lighting/sd_lighting_native/sdnative.cpython-3XX-x86_64-linux-gnu.so   (3.11; 3.13 if built)
           sd_lighting/sd_lighting_native/sdnative_x86_64_v3.cpython-3XX-x86_64-linux-gnu.so   (AVX2/FMA)
           sd_lighting/sd_lighting_native.libs/libembree3-*.so.3, libtbb-*.so.12   (auditwheel's)
    sd_lighting_extension.zip, the Blender 4.2+ extension (Get Extensions > Install from Disk):
           sd_lighting/blender_manifest.toml   (listing the wheels; Blender installs the one of its Python)
           sd_lighting/wheels/sd_lighting_native-*-cp3XX-cp3XX-manylinux_2_35_x86_64.whl

The manifest's schema (1.0.0, Blender 4.2 - 5.0) has no python_versions key, so the manifest
written into the zip also bounds the Blender versions: without a CPython 3.13 wheel it gets
blender_version_max = "5.1.0" (5.1 is the first Blender on 3.13), which the extension installer
honours. native.py picks the module of the running Python's ABI.
"""

import argparse
import io
import os
import re
import subprocess
import sys
import tempfile
import zipfile

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
# The first Blender that no longer runs each CPython of the native modules (None: still current).
BLENDER_AFTER_PYTHON = {(3, 11): "5.1.0", (3, 13): None}
# The manylinux policy the wheels are repaired to (scripts/build.sh): glibc 2.35 (Ubuntu 22.04,
# Fedora 36, Debian 12 and newer), because of the modules' hypot@GLIBC_2.35.
POLICY = "manylinux_2_35_x86_64"

# What the zip's shared objects may load from the system: the libraries of the manylinux policies,
# at the symbol versions of manylinux_2_35 and of GCC 11's libstdc++ (which Debian's Embree needs:
# GLIBCXX_3.4.29). Every other library a module loads (Embree, its TBB) is carried, as auditwheel
# grafted it into the wheel. An independent check of what auditwheel did, and of the zips.
SYSTEM_LIBRARIES = {"linux-vdso.so.1", "ld-linux-x86-64.so.2", "libc.so.6", "libm.so.6", "libpthread.so.0",
                    "libdl.so.2", "librt.so.1", "libgcc_s.so.1", "libstdc++.so.6"}
NEWEST_SYMBOLS = {"GLIBC": (2, 35), "GLIBCXX": (3, 4, 29), "CXXABI": (1, 3, 13), "GCC": (7, 0, 0)}
SHARED_OBJECT = re.compile(r"\.so(\.\d+)*$")


def wheel_python(wheel_path):
    """(3, 11) for sd_lighting_native-0.1.0-cp311-cp311-manylinux_2_35_x86_64.whl."""
    match = re.search(r"-cp3(\d+)-cp3\d+-[^-]+\.whl$", os.path.basename(wheel_path))
    if not match:
        sys.exit("package_addon: not a CPython wheel of the native module: %s" % wheel_path)
    return (3, int(match.group(1)))


def wheel_files(wheel_path):
    """{path: bytes} of what the wheel installs (its package and auditwheel's libraries), without
    its .dist-info."""
    with zipfile.ZipFile(wheel_path) as wheel:
        return {name: wheel.read(name) for name in wheel.namelist()
                if not name.split("/", 1)[0].endswith(".dist-info") and not name.endswith("/")}


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


def violations(files):
    """The policy's violations of the shared objects among `files` ({path: bytes}: one wheel's or
    one zip's), each allowed to load the others."""
    objects = {name: data for name, data in files.items() if SHARED_OBJECT.search(name)}
    carried = {os.path.basename(name) for name in objects}
    with tempfile.TemporaryDirectory() as directory:
        problems = []
        for name, data in objects.items():
            path = os.path.join(directory, os.path.basename(name))
            with open(path, "wb") as f:
                f.write(data)
            problems += policy_violations(path, carried)
        return problems


def check_zip(zip_path):
    """The policy's violations in a written zip: of its shared objects, and of each wheel's in it."""
    with zipfile.ZipFile(zip_path) as archive:
        names = archive.namelist()
        problems = violations({n: archive.read(n) for n in names if SHARED_OBJECT.search(n)})
        for name in names:
            if name.endswith(".whl"):
                problems += violations(wheel_files(io.BytesIO(archive.read(name))))
        if not any(SHARED_OBJECT.search(n) or n.endswith(".whl") for n in names):
            problems.append("%s: carries no native module" % zip_path)
    return problems


def wheel_policy(auditwheel, wheel_path):
    """The platform tag `auditwheel show` finds the wheel consistent with, or None."""
    shown = subprocess.run([auditwheel, "show", wheel_path], capture_output=True, text=True)
    match = re.search(r'consistent\s+with\s+the\s+following\s+platform\s+tag:\s+"([^"]+)"', shown.stdout)
    return match.group(1) if match else None


def manifest_text(path, wheels):
    """The package's blender_manifest.toml for the extension: its wheels listed, and
    blender_version_max from the newest Python among them."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    newest = max(wheel_python(w) for w in wheels)
    if newest not in BLENDER_AFTER_PYTHON:
        sys.exit("package_addon: no Blender range known for CPython %d.%d" % newest)
    maximum = BLENDER_AFTER_PYTHON[newest]
    lines = "# Written by scripts/package_addon.py: the native module, one wheel per CPython.\nwheels = [%s]\n" % (
        ", ".join('"./wheels/%s"' % os.path.basename(w) for w in wheels))
    if maximum and not re.search(r"^blender_version_max\s*=", text, re.M):
        lines += ("# The native module is built for CPython %d.%d only, and Blender %s moved to the next "
                  "Python.\nblender_version_max = \"%s\"\n" % (newest + (maximum, maximum)))
    table = re.search(r"^\[", text, re.M)   # top-level keys go before the first [table]
    at = table.start() if table else len(text)
    return text[:at] + lines + "\n" + text[at:]


def package_files():
    """[(path, arcname)] of the Python package and the shaders, common to both zips."""
    package = os.path.join(ROOT, "addon", "sd_lighting")
    shaders = os.path.join(ROOT, "shaders")
    entries = []
    for directory, subdirectories, names in os.walk(package):
        subdirectories[:] = sorted(d for d in subdirectories if d != "__pycache__")
        for name in sorted(names):
            if name.endswith(".py"):
                path = os.path.join(directory, name)
                entries.append((path, "sd_lighting/" + os.path.relpath(path, package).replace(os.sep, "/")))
    for name in sorted(os.listdir(shaders)):
        if name.endswith(".glsl"):
            entries.append((os.path.join(shaders, name), "sd_lighting/shaders/" + name))
    return entries


def write_zip(output, entries, texts):
    """Writes `entries` ([(path, arcname)]) and `texts` ([(bytes or str, arcname)]) into `output`,
    replacing it only once whole."""
    os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
    temporary = output + ".tmp"
    with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED) as archive:
        for path, arcname in entries:
            archive.write(path, arcname)
        for text, arcname in texts:
            archive.writestr(arcname, text)
    os.replace(temporary, output)
    print("package_addon: wrote %s (%d files, %.1f MB)" % (output, len(entries) + len(texts),
                                                          os.path.getsize(output) / 1e6))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--wheels", help="folder of the repaired wheels (sd_lighting_native-*.whl)")
    parser.add_argument("--output", help="the legacy add-on zip to write")
    parser.add_argument("--extension-output", help="the Blender 4.2+ extension zip to write")
    parser.add_argument("--check", metavar="ZIP", nargs="+",
                        help="only check the shared objects of written zips against the policy (exit 1 if not)")
    parser.add_argument("--wheel-policy", metavar=("AUDITWHEEL", "WHEEL"), nargs="+",
                        help="only check that `auditwheel show` finds each wheel consistent with %s" % POLICY)
    args = parser.parse_args()
    if args.check:
        problems = [line for path in args.check for line in check_zip(path)]
        print("\n".join(problems) or "package_addon: every shared object loads only the policy's system "
                                      "libraries and the ones it carries")
        sys.exit(1 if problems else 0)
    if args.wheel_policy:
        auditwheel, wheels = args.wheel_policy[0], args.wheel_policy[1:]
        tags = {w: wheel_policy(auditwheel, w) for w in wheels}
        for wheel, tag in tags.items():
            print("%s: auditwheel show: consistent with %s" % (os.path.basename(wheel), tag))
        sys.exit(0 if wheels and all(tag == POLICY for tag in tags.values()) else 1)
    if not args.wheels or not args.output or not args.extension_output:
        parser.error("--wheels, --output and --extension-output are required")

    wheels = sorted(os.path.join(args.wheels, n) for n in os.listdir(args.wheels)
                    if n.startswith("sd_lighting_native-") and n.endswith(".whl")) if os.path.isdir(args.wheels) else []
    if not wheels:
        sys.exit("package_addon: no wheel of the native module in %s (scripts/build.sh makes them)" % args.wheels)
    if len({wheel_python(w) for w in wheels}) != len(wheels):
        sys.exit("package_addon: two wheels for one CPython: %s" % ", ".join(wheels))
    installed = {}   # what the wheels install: the same libraries in each
    for wheel in wheels:
        for name, data in wheel_files(wheel).items():
            if installed.setdefault(name, data) != data:
                sys.exit("package_addon: two wheels install different files as %s" % name)
    problems = violations(installed)
    if problems:
        sys.exit("package_addon: beyond the policy of the libraries a user's system has:\n  " + "\n  ".join(problems))

    common = package_files()
    write_zip(args.output, common, [(data, "sd_lighting/" + name) for name, data in sorted(installed.items())])
    manifest = manifest_text(os.path.join(ROOT, "addon", "sd_lighting", "blender_manifest.toml"), wheels)
    write_zip(args.extension_output, common + [(w, "sd_lighting/wheels/" + os.path.basename(w)) for w in wheels],
              [(manifest, "sd_lighting/blender_manifest.toml")])
    print("package_addon: sdnative for %s; carrying %s" % (
        ", ".join("CPython %d.%d" % wheel_python(w) for w in wheels),
        ", ".join(sorted(os.path.basename(n) for n in installed if ".libs/" in n)) or "no library"))


if __name__ == "__main__":
    main()
