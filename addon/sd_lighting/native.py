"""The native module `sdnative` (C++, pybind11): found in the add-on's wheel, or in a development build.

The module ships as the wheel sd_lighting_native, one per CPython it was built for (3.11; 3.13 for
Blender 5.1+: pyproject.toml, scripts/package_addon.py). The extension zip (Blender 4.2+) lists the
wheels, and Blender installs the one of its Python into the extensions' site-packages; the legacy
zip carries their files inside this package, as pip would install them. Either way the package
sd_lighting_native holds `sdnative.cpython-3XX-*.so`; the loader picks the one of the running
Python by its ABI tag. Next to each may be `sdnative_x86_64_v3.cpython-3XX-*.so`, the same module
compiled for x86-64-v3 (AVX2, FMA: native/CMakeLists.txt), loaded instead where the CPU and OS run
that level - as the portable build's `sd_cpu_supports_x86_64_v3` reads it with cpuid, called
through ctypes before either is imported; SDNATIVE_BUILD=sdnative keeps the portable one. For
development without a zip, the directory in the environment variable `SDNATIVE_PATH`, or the
repository's `build/native/`, is searched after those.
"""

import ctypes
import importlib.machinery
import importlib.util
import os

_module = None
_error = None


WHEEL_PACKAGE = "sd_lighting_native"


def _candidate_directories():
    here = os.path.dirname(os.path.abspath(__file__))
    yield os.path.join(here, WHEEL_PACKAGE)   # the legacy zip
    # The extension (bl_ext.<repository>.sd_lighting): the wheel Blender installed into the
    # extensions' site-packages (found, not imported). Only there: that folder outlives an
    # uninstalled extension's session and would shadow a development build.
    if __name__.startswith("bl_ext."):
        try:
            spec = importlib.util.find_spec(WHEEL_PACKAGE)
        except (ImportError, ValueError):
            spec = None
        if spec is not None and spec.submodule_search_locations:
            yield from spec.submodule_search_locations
    env = os.environ.get("SDNATIVE_PATH")
    if env:
        yield env
    # addon/sd_lighting/ inside the repository: ../../build/native
    yield os.path.normpath(os.path.join(here, "..", "..", "build", "native"))


PORTABLE, X86_64_V3 = "sdnative", "sdnative_x86_64_v3"


def supports_x86_64_v3(portable_path):
    """Whether this CPU and OS run x86-64-v3 code, by cpuid in the portable build at `portable_path`
    (opened as a shared library, not imported: native/python/cpu_level.cpp); False where it cannot
    tell."""
    try:   # on Windows a missing folder makes add_dll_directory raise, as a missing file CDLL
        _add_dll_directory(portable_path)
        return bool(ctypes.CDLL(os.path.abspath(portable_path)).sd_cpu_supports_x86_64_v3())
    except (OSError, AttributeError):
        return False


def builds(supports_v3, override=None):
    """The module builds to try, best first: the x86-64-v3 one where the CPU runs it (and
    `override`, $SDNATIVE_BUILD, does not name the portable one), then the portable one."""
    if override == PORTABLE or not supports_v3:
        return [PORTABLE]
    return [X86_64_V3, PORTABLE]


def _add_dll_directory(path):
    """Windows (untested): the DLLs the module loads lie beside it, or where delvewheel put them
    (the wheel's sd_lighting_native.libs, which its package's __init__ would add: it is not imported)."""
    if hasattr(os, "add_dll_directory"):
        folder = os.path.dirname(os.path.abspath(path))
        for directory in (folder, folder + ".libs"):
            if os.path.isdir(directory):
                os.add_dll_directory(directory)


def load_file(path):
    """Imports the module file `path`, of either build: both define PyInit_sdnative, so the
    module is "sdnative" either way."""
    _add_dll_directory(path)
    spec = importlib.util.spec_from_file_location("sdnative", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _load():
    # the interpreter's own suffix (".cpython-311-x86_64-linux-gnu.so", ".cp311-win_amd64.pyd"): a zip
    # may carry other versions' and platforms' builds too
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    for directory in _candidate_directories():
        if not os.path.isdir(directory):
            continue
        names = set(os.listdir(directory))
        if PORTABLE + suffix not in names:
            continue
        portable = os.path.join(directory, PORTABLE + suffix)
        v3 = X86_64_V3 + suffix in names and supports_x86_64_v3(portable)
        for build in builds(v3, os.environ.get("SDNATIVE_BUILD")):
            if build + suffix in names:
                return load_file(os.path.join(directory, build + suffix))
    raise ImportError(
        "sdnative (the add-on's native module, built for %s) was not found in the add-on, in its "
        "wheel %s, in $SDNATIVE_PATH or in the repository's build/native/" % (suffix, WHEEL_PACKAGE))


def get():
    """The sdnative module; raises ImportError with the reason if it cannot be loaded."""
    global _module, _error
    if _module is None:
        if _error is not None:
            raise ImportError(_error)
        try:
            _module = _load()
        except Exception as exc:  # a wrong ABI or a missing library shows up here
            _error = str(exc)
            raise ImportError(_error) from exc
    return _module


def available():
    """True when sdnative can be loaded (the panel shows the reason otherwise)."""
    try:
        get()
        return True
    except ImportError:
        return False


def error_message():
    """Why sdnative could not be loaded, or an empty string."""
    try:
        get()
        return ""
    except ImportError as exc:
        return str(exc)
