"""The lobe designs' cache (live/lobe_designs.py): keys, versioned files validated on load,
builds in a worker thread that never block `get`, continuation from a neighbouring exponent."""

import json
import os
import threading

import numpy as np
import pytest

from sd_lighting.live import lobe_designs
from sd_lighting.live.lobe_designs import Design, DesignFiles, LobeDesigns, design_key


def test_key_per_lobe_exponent_and_degree():
    assert design_key("phong", 8, 6) == ("phong", 8.0, 6)
    assert design_key("phong", 8.0, 6) != design_key("phong", 8.5, 6)
    assert design_key("phong", 8.0, 6) != design_key("phong", 8.0, 7)
    assert design_key("phong", 1.0, 6) != design_key("lambert", 1.0, 6)
    # Lambert has no exponent: one design per degree
    assert design_key("lambert", 1.0, 6) == design_key("lambert", 0.0, 6)
    for bad in (("ggx", 1.0, 6), ("phong", float("nan"), 6), ("phong", -1.0, 6)):
        with pytest.raises(ValueError):
            design_key(*bad)


def test_one_file_per_key(tmp_path, sdnative):
    files = DesignFiles(str(tmp_path), sdnative)
    keys = [design_key("phong", 8.0, 6), design_key("phong", 8.5, 6), design_key("phong", 8.0, 7),
            design_key("lambert", 0.0, 6)]
    assert len({files.path(k) for k in keys}) == len(keys)
    for key in keys:
        nodes, weights = sdnative.zonal_design(key.lobe, key.exponent, key.degree, "gauss")
        files.save(key, Design(np.asarray(nodes), np.asarray(weights), True))
    assert sorted(files.keys()) == sorted(keys)


def _saved(tmp_path, sdnative, key):
    files = DesignFiles(str(tmp_path), sdnative)
    nodes, weights = sdnative.zonal_design(key.lobe, key.exponent, key.degree)
    files.save(key, Design(np.asarray(nodes), np.asarray(weights), True))
    return files, nodes, weights


def test_file_round_trip_is_exact(tmp_path, sdnative):
    key = design_key("phong", 32.0, 6)
    files, nodes, weights = _saved(tmp_path, sdnative, key)
    design = files.load(key)
    assert design.final
    assert np.array_equal(design.nodes, nodes) and np.array_equal(design.weights, weights)
    assert files.load(design_key("phong", 32.0, 7)) is None   # another degree has no file


def _rewrite(path, change):
    with open(path, encoding="utf-8") as f:
        data = json.load(f)
    change(data)
    with open(path, "w", encoding="utf-8") as f:
        json.dump(data, f)


@pytest.mark.parametrize("corruption", ["truncated", "not json", "version", "format", "other key",
                                        "weight", "node", "negative weight", "missing nodes"])
def test_corrupt_file_is_rejected_and_deleted(tmp_path, sdnative, corruption):
    key = design_key("phong", 8.0, 6)
    files, _, _ = _saved(tmp_path, sdnative, key)
    path = files.path(key)
    if corruption == "truncated":
        text = open(path, encoding="utf-8").read()
        open(path, "w", encoding="utf-8").write(text[:len(text) // 2])
    elif corruption == "not json":
        open(path, "wb").write(b"\x00\xff garbage")
    elif corruption == "version":
        _rewrite(path, lambda d: d.update(version=lobe_designs.VERSION + 1))
    elif corruption == "format":
        _rewrite(path, lambda d: d.update(format="something else"))
    elif corruption == "other key":   # a valid design, but of sigma 9 under sigma 8's name
        _rewrite(path, lambda d: d.update(exponent=9.0))
    elif corruption == "weight":      # one digit off: the moments no longer match
        _rewrite(path, lambda d: d["weights"].__setitem__(0, d["weights"][0] * (1 + 1e-6)))
    elif corruption == "node":
        _rewrite(path, lambda d: d["nodes"].__setitem__(0, [0.0, 0.0, 1.0]))
    elif corruption == "negative weight":
        _rewrite(path, lambda d: d["weights"].__setitem__(0, -d["weights"][0]))
    elif corruption == "missing nodes":
        _rewrite(path, lambda d: d.pop("nodes"))
    assert files.load(key) is None
    assert not os.path.exists(path)


def test_certify_measures_the_moments(sdnative):
    key = design_key("phong", 8.0, 6)
    nodes, weights = sdnative.zonal_design("phong", 8.0, 6)
    assert lobe_designs.certify(sdnative, key, nodes, weights) <= sdnative.DESIGN_TOLERANCE
    with pytest.raises(ValueError, match="moment residual"):   # a design of another lobe
        lobe_designs.certify(sdnative, design_key("phong", 8.5, 6), nodes, weights)
    with pytest.raises(ValueError, match="moment residual"):   # of a lower degree
        lower = sdnative.zonal_design("phong", 8.0, 4)
        lobe_designs.certify(sdnative, key, *lower)


class _Recording:
    """sdnative, with the design builders recorded and held until `release` is set."""

    def __init__(self, sdnative):
        self._sd = sdnative
        self.calls = []
        self.release = threading.Event()
        self.release.set()

    def __getattr__(self, name):
        return getattr(self._sd, name)

    def zonal_design(self, lobe, exponent, degree, method="auto"):
        self.calls.append(("zonal_design", exponent, degree, method))
        if method != "gauss":
            self.release.wait(30)
        return self._sd.zonal_design(lobe, exponent, degree, method)

    def zonal_design_continued(self, lobe, exponent, degree, start_exponent, nodes, weights, thin=True):
        self.calls.append(("zonal_design_continued", exponent, degree, start_exponent, thin))
        self.release.wait(30)
        return self._sd.zonal_design_continued(lobe, exponent, degree, start_exponent, nodes, weights, thin=thin)


def test_get_never_waits_for_a_build(tmp_path, sdnative):
    sd = _Recording(sdnative)
    sd.release.clear()   # the build cannot finish before the test lets it
    designs = LobeDesigns(sd, str(tmp_path))
    key = design_key("phong", 32.0, 8)
    standin = designs.get("phong", 32.0, 8)
    assert not standin.final
    assert len(standin.weights) == len(sdnative.zonal_design("phong", 32.0, 8, "gauss")[1])
    lobe_designs.certify(sdnative, key, standin.nodes, standin.weights)
    assert designs.pending() == [key]
    assert designs.get("phong", 32.0, 8) is standin   # asked again while building
    sd.release.set()
    assert designs.wait(60)
    final = designs.get("phong", 32.0, 8)
    assert final.final and len(final.weights) < len(standin.weights)
    assert designs.generation == 1
    assert os.path.exists(designs.files.path(key))
    assert [c[0] for c in sd.calls] == ["zonal_design", "zonal_design"]   # Gauss, then the search


def test_a_new_session_reads_the_file_without_building(tmp_path, sdnative):
    first = LobeDesigns(sdnative, str(tmp_path))
    first.get("lambert", 1.0, 7)
    assert first.wait(60)
    built = first.get("lambert", 1.0, 7)
    sd = _Recording(sdnative)
    second = LobeDesigns(sd, str(tmp_path))
    loaded = second.get("lambert", 1.0, 7)
    assert loaded.final and np.array_equal(loaded.nodes, built.nodes)
    assert sd.calls == [] and second.pending() == []


def test_a_corrupt_file_is_rebuilt(tmp_path, sdnative):
    key = design_key("phong", 8.0, 6)
    path = DesignFiles(str(tmp_path), sdnative).path(key)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    open(path, "w", encoding="utf-8").write('{"format": "%s", "version": %d}' % (
        lobe_designs.FORMAT, lobe_designs.VERSION))
    designs = LobeDesigns(sdnative, str(tmp_path))
    assert not designs.get("phong", 8.0, 6).final
    assert designs.wait(60)
    assert designs.get("phong", 8.0, 6).final
    assert DesignFiles(str(tmp_path), sdnative).load(key) is not None


def test_builds_continue_from_the_nearest_exponent(tmp_path, sdnative):
    for exponent in (8.0, 64.0, 1000.0):
        _saved(tmp_path, sdnative, design_key("phong", exponent, 6))
    _saved(tmp_path, sdnative, design_key("phong", 30.0, 7))   # another degree: not a start
    sd = _Recording(sdnative)
    designs = LobeDesigns(sd, str(tmp_path))
    designs.get("phong", 40.0, 6)
    assert designs.wait(60)
    # from 64 towards 40 in steps of at most CONTINUATION_STEP in sigma + 1
    steps = [c for c in sd.calls if c[0] == "zonal_design_continued"]
    assert steps[0][3] == 64.0 and steps[-1][1] == 40.0
    assert all(1.0 / 1.25 - 1e-12 <= (b[1] + 1) / (b[3] + 1) < 1.0 for b in steps)
    assert [b[4] for b in steps] == [False] * (len(steps) - 1) + [True]   # thinned where it ends
    assert not [c for c in sd.calls if c[0] == "zonal_design" and c[3] != "gauss"]
    final = designs.get("phong", 40.0, 6)
    assert final.final
    lobe_designs.certify(sdnative, design_key("phong", 40.0, 6), final.nodes, final.weights)


def test_lambert_and_phong_continue_into_each_other(tmp_path, sdnative):
    _saved(tmp_path, sdnative, design_key("lambert", 1.0, 6))   # Phong sigma = 1
    sd = _Recording(sdnative)
    designs = LobeDesigns(sd, str(tmp_path))
    designs.get("phong", 1.2, 6)
    assert designs.wait(60)
    assert ("zonal_design_continued", 1.2, 6, 1.0, True) in sd.calls
    assert designs.get("phong", 1.2, 6).final


def test_an_unwritable_cache_still_builds(tmp_path, sdnative):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    designs = LobeDesigns(sdnative, str(blocker / "designs"))
    designs.get("phong", 8.0, 5)
    assert designs.wait(60)
    assert designs.get("phong", 8.0, 5).final


def test_close_drops_the_queue(tmp_path, sdnative):
    sd = _Recording(sdnative)
    sd.release.clear()
    designs = LobeDesigns(sd, str(tmp_path))
    designs.get("phong", 8.0, 6)
    designs.get("phong", 9.0, 6)
    designs.close()
    assert designs.pending() == []
    sd.release.set()
    assert designs.wait(60)
    assert not designs.get("phong", 8.0, 6).final   # the result of the running build was dropped
    assert designs.pending() == []
