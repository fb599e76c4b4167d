"""The add-on's bpy-free modules, tested with plain Python (no Blender): the package is imported
from addon/, sdnative (where a test needs it) from PYTHONPATH or the add-on's own loader."""

import os
import sys

ADDON = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "addon"))
if ADDON not in sys.path:
    sys.path.insert(0, ADDON)

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def sdnative():
    from sd_lighting import native
    return native.get()


@pytest.fixture(scope="session")
def glsl_source():
    """The add-on's GLSL files, concatenated."""
    shaders = os.path.join(ADDON, "..", "shaders")
    return "".join(open(os.path.join(shaders, name), encoding="utf-8").read()
                   for name in sorted(os.listdir(shaders)) if name.endswith(".glsl"))
