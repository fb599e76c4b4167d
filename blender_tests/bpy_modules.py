#!/usr/bin/env python3
"""Blender as a Python module: the pinned `bpy` wheels (blender_tests/bpy_versions.txt), each in a
virtual environment of its own, cached outside the repository so that reruns cost nothing.

    python3 blender_tests/bpy_modules.py install [VERSION ...]   # idempotent; default: all pinned, and the tools
    python3 blender_tests/bpy_modules.py python VERSION          # prints that version's interpreter
    python3 blender_tests/bpy_modules.py list                    # the pinned versions
    python3 blender_tests/bpy_modules.py find-python 3.13        # a CPython 3.13 on this machine

Cache: $SD_BPY_CACHE, else ${XDG_CACHE_HOME:-~/.cache}/sd-lighting: wheels/ (the downloaded bpy
wheels, 350-430 MB each) and venv/bpy-VERSION/ (about 1 GB each). A venv counts as installed when
its marker file names the same version, Python and pinned dependencies
(bpy_constraints-<python>.txt); otherwise it is built again. Each venv is made with the CPython the
pin names (3.11: Debian's /usr/bin/python3, whose `venv` module is Debian's python3-venv; 3.13:
python3.13 on PATH or pyenv's). A version whose CPython is not on the machine is skipped.

The tools: the packages the tests use besides Blender's own (tools_requirements.txt: NVIDIA's
FLIP), in venv/tools/, a venv of Debian's CPython 3.11 that sees its system packages (NumPy);
`install` without versions makes it too, and sdtest.py puts its site-packages on the path.
"""

import argparse
import glob
import hashlib
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
VERSIONS_FILE = os.path.join(HERE, "bpy_versions.txt")
MARKER = ".sd-lighting-installed"
DEFAULT_PYTHON = "3.11"


def pins():
    """{bpy version: CPython "3.x" it needs}, in file order."""
    out = {}
    with open(VERSIONS_FILE, encoding="utf-8") as f:
        for line in f:
            fields = line.split("#", 1)[0].split()
            if fields and fields[0].startswith("bpy=="):
                python = DEFAULT_PYTHON
                for field in fields[1:]:
                    if field.startswith("python="):
                        python = field[len("python="):]
                out[fields[0][len("bpy=="):]] = python
    return out


def versions():
    return list(pins())


def constraints_file(python):
    return os.path.join(HERE, "bpy_constraints-%s.txt" % python)


def find_python(python):
    """A CPython `python` ("3.13") interpreter on this machine, or None: $SD_PYTHON313,
    /usr/bin/python3.13 (and /usr/bin/python3 for Debian's own), python3.13 on PATH, pyenv's."""
    digits = python.replace(".", "")
    candidates = [os.environ.get("SD_PYTHON" + digits), "/usr/bin/python" + python]
    if python == "3.11":
        candidates.append("/usr/bin/python3")
    candidates.append(shutil.which("python" + python))
    pyenv = os.environ.get("PYENV_ROOT") or os.path.join(os.path.expanduser("~"), ".pyenv")
    candidates += sorted(glob.glob(os.path.join(pyenv, "versions", python + "*", "bin", "python" + python)),
                         reverse=True)
    for candidate in candidates:
        if not candidate or not os.access(candidate, os.X_OK):
            continue
        probe = subprocess.run([candidate, "-c", "import sys, venv; print('%d.%d' % sys.version_info[:2])"],
                               capture_output=True, text=True)
        if probe.returncode == 0 and probe.stdout.strip() == python:
            return candidate
    return None


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
    python = pins()[version]
    with open(constraints_file(python), "rb") as f:
        constraints = hashlib.sha256(f.read()).hexdigest()[:16]
    return "bpy==%s python=%s constraints=%s\n" % (version, python, constraints)


def _marked(venv, expected):
    """Whether the venv's marker file holds `expected` (what it was made with)."""
    try:
        with open(os.path.join(venv, MARKER), encoding="utf-8") as f:
            return f.read() == expected
    except OSError:
        return False


def _mark(venv, text):
    with open(os.path.join(venv, MARKER), "w", encoding="utf-8") as f:
        f.write(text)


def installed(version):
    return _marked(venv_directory(version), _expected_marker(version))


def _run(command, **kwargs):
    subprocess.run(command, check=True, **kwargs)


def _quiet_pip(python, *arguments):
    return [python, "-m", "pip", "--disable-pip-version-check", "--no-input", "-q", *arguments]


def install(version):
    """Makes the version's venv (downloading the wheel when it is not cached). Returns the seconds
    spent (0 when it was already there), or None when its CPython is not on this machine."""
    if installed(version):
        return 0.0
    python_version = pins()[version]
    base = find_python(python_version)
    if base is None:
        print("bpy_modules: bpy %s needs CPython %s, not found here: skipped" % (version, python_version))
        return None
    start = time.perf_counter()
    wheels = os.path.join(cache_directory(), "wheels")
    venv = venv_directory(version)
    os.makedirs(wheels, exist_ok=True)
    shutil.rmtree(venv, ignore_errors=True)
    _run([base, "-m", "venv", venv])
    python = interpreter(version)
    prefix = "bpy-%s-" % version
    if not any(name.startswith(prefix) and name.endswith(".whl") for name in os.listdir(wheels)):
        print("bpy_modules: downloading bpy %s ..." % version, flush=True)
        t = time.perf_counter()
        _run(_quiet_pip(python, "download", "--no-deps", "--only-binary=:all:", "--no-cache-dir",
                        "--dest", wheels, "bpy==" + version))
        print("bpy_modules: downloaded bpy %s in %.0f s" % (version, time.perf_counter() - t), flush=True)
    print("bpy_modules: installing bpy %s (CPython %s) into %s ..." % (version, python_version, venv),
          flush=True)
    _run(_quiet_pip(python, "install", "--no-cache-dir", "--find-links", wheels,
                    "--constraint", constraints_file(python_version), "bpy==" + version))
    probe = subprocess.run([python, "-c", "import bpy; print(bpy.app.version_string)"],
                           capture_output=True, text=True)
    if probe.returncode != 0 or not probe.stdout.strip().startswith(version):
        raise SystemExit("bpy_modules: bpy %s does not import in %s:\n%s%s" % (
            version, venv, probe.stdout, probe.stderr))
    _mark(venv, _expected_marker(version))
    seconds = time.perf_counter() - start
    print("bpy_modules: bpy %s ready in %.0f s" % (version, seconds), flush=True)
    return seconds


TOOLS_REQUIREMENTS = os.path.join(HERE, "tools_requirements.txt")


def tools_directory():
    return os.path.join(cache_directory(), "venv", "tools")


def tools_site_packages():
    """The tools venv's site-packages (for sys.path), whether installed or not."""
    return os.path.join(tools_directory(), "lib", "python" + DEFAULT_PYTHON, "site-packages")


def _tools_marker():
    with open(TOOLS_REQUIREMENTS, "rb") as f:
        return "tools python=%s requirements=%s\n" % (DEFAULT_PYTHON, hashlib.sha256(f.read()).hexdigest()[:16])


def install_tools():
    """Makes the tools venv (tools_requirements.txt) unless it holds the same pins. Returns the
    seconds spent (0 when it was already there), or None without a CPython 3.11 here."""
    venv = tools_directory()
    if _marked(venv, _tools_marker()):
        return 0.0
    base = find_python(DEFAULT_PYTHON)
    if base is None:
        print("bpy_modules: the tools need CPython %s, not found here: skipped" % DEFAULT_PYTHON)
        return None
    start = time.perf_counter()
    shutil.rmtree(venv, ignore_errors=True)
    _run([base, "-m", "venv", "--system-site-packages", venv])
    python = os.path.join(venv, "bin", "python")
    print("bpy_modules: installing the tools into %s ..." % venv, flush=True)
    _run(_quiet_pip(python, "install", "--no-deps", "--only-binary=:all:", "-r", TOOLS_REQUIREMENTS))
    _mark(venv, _tools_marker())
    seconds = time.perf_counter() - start
    print("bpy_modules: the tools ready in %.0f s" % seconds, flush=True)
    return seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("install")
    p.add_argument("versions", nargs="*")
    p = sub.add_parser("python")
    p.add_argument("version")
    p = sub.add_parser("find-python")
    p.add_argument("python", help='"3.13"')
    sub.add_parser("list")
    args = parser.parse_args()
    pinned = versions()
    if args.command == "list":
        print("\n".join(pinned))
    elif args.command == "python":
        print(interpreter(args.version))
    elif args.command == "find-python":
        found = find_python(args.python)
        if found is None:
            return 1
        print(found)
    else:
        unknown = set(args.versions) - set(pinned)
        if unknown:
            parser.error("not pinned in %s: %s" % (VERSIONS_FILE, ", ".join(sorted(unknown))))
        for version in args.versions or pinned:
            if installed(version):
                print("bpy_modules: bpy %s is installed (%s)" % (version, venv_directory(version)))
            else:
                install(version)
        if not args.versions:
            install_tools()
    return 0


if __name__ == "__main__":
    sys.exit(main())
