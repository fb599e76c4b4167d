"""Shared fixtures for the Python tests of the native module `sdnative`.

The module must be importable (build target `sdnative`, then PYTHONPATH=<build>/native): a missing
module is an error of the whole suite, never a skip.
"""
import os
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

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
