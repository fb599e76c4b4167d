"""Shared fixtures for the Python tests of the native module `sdnative`.

The module must be importable (build target `sdnative`, then PYTHONPATH=<build>/native): a missing
module is an error of the whole suite, never a skip. SDNATIVE_FILE names another build of it to
test instead (the x86-64-v3 one: tests/CMakeLists.txt); on a CPU that cannot run that build the
suite exits with 77, which CTest reports as skipped.
"""
import os
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def _load_file(path):
    """Imports the module file `path` as "sdnative", where this CPU can run its build."""
    sys.path.insert(0, os.path.join(HERE, "..", "..", "addon"))
    from sd_lighting import native   # which builds this CPU runs: cpuid in the portable build beside it
    build, _, suffix = os.path.basename(path).partition(".")
    portable = os.path.join(os.path.dirname(path), native.PORTABLE + "." + suffix)
    if build not in native.builds(native.supports_x86_64_v3(portable)):
        pytest.exit("this CPU cannot run %s" % os.path.basename(path), returncode=77)
    sys.modules["sdnative"] = native.load_file(path)


if os.environ.get("SDNATIVE_FILE"):
    _load_file(os.environ["SDNATIVE_FILE"])

try:
    import sdnative  # noqa: E402
except ImportError as error:  # fail loudly, with a hint
    raise ImportError(
        "cannot import the native module 'sdnative': build the CMake target 'sdnative' and put its "
        "directory (e.g. <build>/native) on PYTHONPATH; run under /usr/bin/python3, the interpreter "
        f"it is built for (running {sys.executable}). Original error: {error}"
    ) from error


@pytest.fixture(scope="session")
def sd():
    return sdnative


@pytest.fixture
def rng():
    return np.random.default_rng(20240611)
