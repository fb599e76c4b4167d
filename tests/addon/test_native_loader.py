"""native.py: which build of sdnative it loads (the x86-64-v3 one only where the CPU has the level's
features), and that both builds bake the same numbers."""

import json
import os
import subprocess
import sys

import pytest

from sd_lighting import native

V3_FLAGS = ("fpu sse sse2 pni ssse3 sse4_1 sse4_2 cx16 lahf_lm popcnt avx avx2 bmi1 bmi2 f16c fma abm "
            "movbe xsave")


def write_cpuinfo(tmp_path, flags):
    path = tmp_path / "cpuinfo"
    path.write_text("processor\t: 0\nmodel name\t: test\nflags\t\t: %s\n\nprocessor\t: 1\nflags\t\t: fpu\n" % flags)
    return str(path)


def test_the_first_processors_flags_are_read(tmp_path):
    assert native.cpu_features(write_cpuinfo(tmp_path, V3_FLAGS)) == frozenset(V3_FLAGS.split())


def test_an_unreadable_cpuinfo_has_no_features(tmp_path):
    assert native.cpu_features(str(tmp_path / "missing")) == frozenset()


def test_the_v3_build_comes_first_only_with_every_feature_of_the_level():
    features = frozenset(V3_FLAGS.split())
    assert native.builds(features) == [native.X86_64_V3, native.PORTABLE]
    for missing in sorted(native.X86_64_V3_FEATURES):
        assert native.builds(features - {missing}) == [native.PORTABLE], missing
    assert native.builds(frozenset()) == [native.PORTABLE]


def test_the_override_keeps_the_portable_build():
    features = frozenset(V3_FLAGS.split())
    assert native.builds(features, "sdnative") == [native.PORTABLE]
    assert native.builds(features, "something else") == [native.X86_64_V3, native.PORTABLE]


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


# The add-on's builds (the zip's): the test module beside them in build/native has only the portable one.
ADDON_BUILDS = os.environ.get("SDNATIVE_ADDON_PATH") or os.path.join(
    os.path.dirname(__file__), "..", "..", "build", "native", "addon")


def bake_with(build):
    environment = dict(os.environ, SDNATIVE_BUILD=build, SDNATIVE_PATH=os.path.abspath(ADDON_BUILDS))
    script = BAKE % os.path.dirname(os.path.dirname(native.__file__))
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=environment,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_both_builds_load_and_bake_the_same():
    if not native.X86_64_V3_FEATURES <= native.cpu_features():
        pytest.skip("this CPU lacks x86-64-v3: only the portable build can run here")
    v3, portable = bake_with(""), bake_with(native.PORTABLE)
    assert os.path.basename(v3["file"]).startswith(native.X86_64_V3 + "."), v3["file"]
    assert os.path.basename(portable["file"]).startswith(native.PORTABLE + "."), portable["file"]
    # The same rays: AO to the bit; the SH sums differ only by FMA's rounding.
    assert v3["ao"] == portable["ao"]
    for key in ("transfer", "products"):
        assert max(abs(a - b) for a, b in zip(v3[key], portable[key])) < 1e-12, key
    assert max(v3["residual"], portable["residual"]) <= 1e-10
