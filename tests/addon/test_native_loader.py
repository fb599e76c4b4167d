"""native.py: which build of sdnative it loads (the x86-64-v3 one only where the CPU has the level's
features), and that both builds bake the same numbers."""

import importlib.machinery
import json
import os
import subprocess
import sys

import pytest

from sd_lighting import native

# The x86-64-v3 level's features, with the v2 ones it includes, as /proc/cpuinfo names them (lzcnt
# is "abm", sse3 "pni"): the reference the loader's cpuid is checked against, where Linux gives one.
V3_FLAGS = frozenset({"cx16", "lahf_lm", "popcnt", "pni", "ssse3", "sse4_1", "sse4_2", "avx", "avx2", "bmi1",
                      "bmi2", "f16c", "fma", "abm", "movbe", "xsave"})

# The add-on's builds (the zip's): the test module beside them in build/native has only the portable one.
ADDON_BUILDS = os.environ.get("SDNATIVE_ADDON_PATH") or os.path.join(
    os.path.dirname(__file__), "..", "..", "build", "native", "addon")


def portable_build():
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    return os.path.join(ADDON_BUILDS, native.PORTABLE + suffix)


def cpuinfo_flags():
    with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
        return frozenset(next(line for line in f if line.startswith("flags")).partition(":")[2].split())


def test_cpuid_finds_the_level_where_proc_cpuinfo_lists_its_features():
    if not os.path.exists("/proc/cpuinfo"):
        pytest.skip("no /proc/cpuinfo to compare with")
    assert native.supports_x86_64_v3(portable_build()) == (V3_FLAGS <= cpuinfo_flags())


def test_a_module_that_cannot_be_opened_answers_no(tmp_path):
    assert native.supports_x86_64_v3(str(tmp_path / "missing.so")) is False
    not_a_library = tmp_path / "sdnative.so"
    not_a_library.write_text("not a shared library")
    assert native.supports_x86_64_v3(str(not_a_library)) is False


def test_a_folder_windows_cannot_add_answers_no(tmp_path, monkeypatch):
    def add_dll_directory(path):   # Windows' answer for a folder that is not there
        raise FileNotFoundError(path)

    monkeypatch.setattr(native.os, "add_dll_directory", add_dll_directory, raising=False)
    assert native.supports_x86_64_v3(str(tmp_path / "gone" / "sdnative.pyd")) is False


def test_the_v3_build_comes_first_only_where_the_cpu_runs_it():
    assert native.builds(True) == [native.X86_64_V3, native.PORTABLE]
    assert native.builds(False) == [native.PORTABLE]


def test_the_override_keeps_the_portable_build():
    assert native.builds(True, "sdnative") == [native.PORTABLE]
    assert native.builds(True, "something else") == [native.X86_64_V3, native.PORTABLE]


BAKE = """
import json, sys
import numpy as np
sys.path.insert(0, %r)
from sd_lighting import native
sd = native.get()
# an octahedron above a ground quad: self-shadowing, floor shadows
vertices = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
triangles = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
ground = np.array([[-3, -3, -1.2], [3, -3, -1.2], [3, 3, -1.2], [-3, 3, -1.2]], float)
out = sd.bake_transfer(vertices, vertices, triangles, 512, transfer_order=4, product_orders=(3, 2),
                       design_orders=(2, 2), occluder_vertices=ground,
                       occluder_triangles=np.array([[0, 1, 2], [0, 2, 3]]), threads=1)
print(json.dumps({"file": sd.__file__, "ao": out["ambient_occlusion"].tolist(),
                  "transfer": out["transfer"].ravel().tolist(),
                  "products": out["product_matrices"].ravel().tolist(),
                  "residual": float(out["design_residuals"].max())}))
"""


def bake_with(build):
    environment = dict(os.environ, SDNATIVE_BUILD=build, SDNATIVE_PATH=os.path.abspath(ADDON_BUILDS))
    script = BAKE % os.path.dirname(os.path.dirname(native.__file__))
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=environment,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_both_builds_load_and_bake_the_same():
    if not native.supports_x86_64_v3(portable_build()):
        pytest.skip("this CPU lacks x86-64-v3: only the portable build can run here")
    v3, portable = bake_with(""), bake_with(native.PORTABLE)
    assert os.path.basename(v3["file"]).startswith(native.X86_64_V3 + "."), v3["file"]
    assert os.path.basename(portable["file"]).startswith(native.PORTABLE + "."), portable["file"]
    # The same rays: AO to the bit; the SH sums differ only by FMA's rounding.
    assert v3["ao"] == portable["ao"]
    for key in ("transfer", "products"):
        assert max(abs(a - b) for a, b in zip(v3[key], portable[key])) < 1e-12, key
    assert max(v3["residual"], portable["residual"]) <= 1e-10
