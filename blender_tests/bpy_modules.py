#!/usr/bin/env python3
"""Blender as a Python module: the pinned `bpy` wheels (blender_tests/bpy_versions.txt), each in a
virtual environment of its own, cached outside the repository so that reruns cost nothing.

    python3 blender_tests/bpy_modules.py install [VERSION ...]   # idempotent; default: all pinned
    python3 blender_tests/bpy_modules.py python VERSION          # prints that version's interpreter
    python3 blender_tests/bpy_modules.py list                    # the pinned versions

Cache: $SD_BPY_CACHE, else ${XDG_CACHE_HOME:-~/.cache}/sd-lighting: wheels/ (the downloaded bpy
wheels, 350-375 MB each) and venv/bpy-VERSION/ (about 1 GB each). A venv counts as installed when
its marker file names the same version and the same pinned dependencies (bpy_constraints.txt);
otherwise it is built again. The venvs are made with the CPython 3.11 that runs this script
(Debian's /usr/bin/python3 in the test command; its `venv` module is Debian's python3-venv).
"""

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
VERSIONS_FILE = os.path.join(HERE, "bpy_versions.txt")
CONSTRAINTS_FILE = os.path.join(HERE, "bpy_constraints.txt")
MARKER = ".sd-lighting-installed"


def versions():
    """The pinned bpy versions, in file order."""
    out = []
    with open(VERSIONS_FILE, encoding="utf-8") as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line.startswith("bpy=="):
                out.append(line[len("bpy=="):])
    return out


def cache_directory():
    if os.environ.get("SD_BPY_CACHE"):
        return os.path.abspath(os.environ["SD_BPY_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "sd-lighting")


def venv_directory(version):
    return os.path.join(cache_directory(), "venv", "bpy-" + version)


def interpreter(version):
    """The Python of the version's venv (whether installed or not)."""
    return os.path.join(venv_directory(version), "bin", "python")


def _expected_marker(version):
    with open(CONSTRAINTS_FILE, "rb") as f:
        constraints = hashlib.sha256(f.read()).hexdigest()[:16]
    return "bpy==%s constraints=%s python=%d.%d\n" % (version, constraints, *sys.version_info[:2])


def installed(version):
    try:
        with open(os.path.join(venv_directory(version), MARKER), encoding="utf-8") as f:
            return f.read() == _expected_marker(version)
    except OSError:
        return False


def _run(command, **kwargs):
    subprocess.run(command, check=True, **kwargs)


def _quiet_pip(python, *arguments):
    return [python, "-m", "pip", "--disable-pip-version-check", "--no-input", "-q", *arguments]


def install(version):
    """Makes the version's venv (downloading the wheel when it is not cached); returns seconds
    spent, 0 when it was already there."""
    if installed(version):
        return 0.0
    if sys.version_info[:2] != (3, 11):
        raise SystemExit("bpy_modules: the bpy %s wheel needs CPython 3.11, this is %s (run it with "
                         "/usr/bin/python3)" % (version, sys.version.split()[0]))
    start = time.perf_counter()
    wheels = os.path.join(cache_directory(), "wheels")
    venv = venv_directory(version)
    os.makedirs(wheels, exist_ok=True)
    shutil.rmtree(venv, ignore_errors=True)
    _run([sys.executable, "-m", "venv", venv])
    python = interpreter(version)
    prefix = "bpy-%s-" % version
    if not any(name.startswith(prefix) and name.endswith(".whl") for name in os.listdir(wheels)):
        print("bpy_modules: downloading bpy %s ..." % version, flush=True)
        t = time.perf_counter()
        _run(_quiet_pip(python, "download", "--no-deps", "--only-binary=:all:", "--no-cache-dir",
                        "--dest", wheels, "bpy==" + version))
        print("bpy_modules: downloaded bpy %s in %.0f s" % (version, time.perf_counter() - t), flush=True)
    print("bpy_modules: installing bpy %s into %s ..." % (version, venv), flush=True)
    _run(_quiet_pip(python, "install", "--no-cache-dir", "--find-links", wheels,
                    "--constraint", CONSTRAINTS_FILE, "bpy==" + version))
    # It must import and be the pinned version (this also compiles nothing: bpy is a binary).
    probe = subprocess.run([python, "-c", "import bpy; print(bpy.app.version_string)"],
                           capture_output=True, text=True)
    if probe.returncode != 0 or not probe.stdout.strip().startswith(version):
        raise SystemExit("bpy_modules: bpy %s does not import in %s:\n%s%s" % (
            version, venv, probe.stdout, probe.stderr))
    with open(os.path.join(venv, MARKER), "w", encoding="utf-8") as f:
        f.write(_expected_marker(version))
    seconds = time.perf_counter() - start
    print("bpy_modules: bpy %s ready in %.0f s" % (version, seconds), flush=True)
    return seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("install")
    p.add_argument("versions", nargs="*")
    p = sub.add_parser("python")
    p.add_argument("version")
    sub.add_parser("list")
    args = parser.parse_args()
    pinned = versions()
    if args.command == "list":
        print("\n".join(pinned))
    elif args.command == "python":
        print(interpreter(args.version))
    else:
        unknown = set(args.versions) - set(pinned)
        if unknown:
            parser.error("not pinned in %s: %s" % (VERSIONS_FILE, ", ".join(sorted(unknown))))
        for version in args.versions or pinned:
            if installed(version):
                print("bpy_modules: bpy %s is installed (%s)" % (version, venv_directory(version)))
            else:
                install(version)
    return 0


if __name__ == "__main__":
    sys.exit(main())
