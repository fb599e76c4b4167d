"""The lobe designs of Theorem 2.1, eq. (12), for the live shading: built once per lobe, exponent
and degree s + s', off the main thread, kept in memory and on disk.

sdnative.zonal_design searches for the smallest design and takes from milliseconds (degree <= 8)
to minutes (degree 18 and up); the draw must never wait for it. `LobeDesigns.get` answers at once
with the design from memory or from its file, or else with the Gauss product rule of the same
degree (msd-notes, "Gauss product": certified, built in milliseconds, only more nodes, so the
shading is already exact) while one worker thread builds the small design - continued from the
design of the nearest exponent already known through the lobes in between, which is much faster
than a search from scratch (sdnative.zonal_design_continued) - and stores it.

Files: one JSON file per design, `<directory>/<lobe>-<exponent>-<degree>.json`, holding FORMAT,
VERSION, the key and the nodes and weights as exact decimal doubles. A file is used only after its
moments have been checked against the lobe's (`certify`); one that fails - truncated, edited, of
another version or key - is deleted and the design rebuilt.

Nothing here needs Blender; the sdnative module is passed in.
"""

import json
import logging
import math
import os
import tempfile
import threading
from collections import namedtuple
from dataclasses import dataclass

import numpy as np

from .. import background

log = logging.getLogger(__name__)

FORMAT = "sd_lighting lobe design"
VERSION = 1
LOBES = ("lambert", "phong")
# Continuation steps: sigma + 1 changes by at most this factor per step (tens of milliseconds at
# degree 10; 1.25 almost always certifies, twice that often does not). A step that fails is
# halved for the rest of the way (growing it back fails again: measured at degrees 12, 14); after
# CONTINUATION_HALVINGS halvings the build searches from scratch instead.
CONTINUATION_STEP = 1.25
CONTINUATION_HALVINGS = 4

DesignKey = namedtuple("DesignKey", "lobe exponent degree")


def design_key(lobe, exponent, degree):
    """The key of a lobe's design: Lambert's weight has no exponent (sdnative ignores it), so
    every Lambert design of a degree shares one key."""
    if lobe not in LOBES:
        raise ValueError("unknown lobe %r (expected one of %s)" % (lobe, ", ".join(LOBES)))
    exponent = 0.0 if lobe == "lambert" else float(exponent)
    if not math.isfinite(exponent) or exponent < 0.0:
        raise ValueError("the exponent must be finite and >= 0, got %r" % exponent)
    return DesignKey(lobe, exponent, int(degree))


def default_directory():
    """$XDG_CACHE_HOME/sd_lighting/lobe_designs (~/.cache without it), where Blender on Linux
    keeps its own caches."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "sd_lighting", "lobe_designs")


@dataclass(frozen=True)
class Design:
    nodes: np.ndarray      # float64 [N, 3], unit vectors around +z
    weights: np.ndarray    # float64 [N], positive, summing to 1
    final: bool            # False: the Gauss product rule standing in while the small one builds

    def texels(self):
        """float32 [N, 4]: x, y, z, lambda (the shader's `design` array)."""
        out = np.empty((len(self.weights), 4), dtype=np.float32)
        out[:, :3] = self.nodes
        out[:, 3] = self.weights
        return out


def certify(sdnative, key, nodes, weights):
    """The moment residual of a design for the key's lobe, ||sum_v lambda_v y(x_v) - integral of
    y w||_2 over every y_lm with l <= degree (eq. 11; the lobe's mass is 1), as sdnative certifies
    its own designs. Raises ValueError for anything that is not a certified design of the key."""
    nodes = np.asarray(nodes, dtype=np.float64)
    weights = np.asarray(weights, dtype=np.float64)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or len(nodes) == 0 or weights.shape != (len(nodes),):
        raise ValueError("a design needs nodes (N, 3) and weights (N,), N >= 1")
    if not (np.all(np.isfinite(nodes)) and np.all(np.isfinite(weights))):
        raise ValueError("a design must be finite")
    if not np.all(weights > 0.0):
        raise ValueError("a design's weights must be positive")
    if np.max(np.abs(np.linalg.norm(nodes, axis=1) - 1.0)) > 1e-12:
        raise ValueError("a design's nodes must be unit vectors")
    degree = key.degree
    moments = np.asarray(sdnative.sh_basis(degree, nodes)).T @ weights
    factors = np.asarray(sdnative.zonal_coefficients(key.lobe, key.exponent, degree))
    target = np.zeros_like(moments)
    for l in range(degree + 1):  # Funk-Hecke: the moment of y_l0 is sqrt(2l+1) w_l, others 0
        target[l * l + l] = math.sqrt(2 * l + 1) * factors[l]
    residual = float(np.linalg.norm(moments - target))
    if not residual <= float(sdnative.DESIGN_TOLERANCE):
        raise ValueError("not a design of %s: moment residual %.3g" % (key, residual))
    return residual


class DesignFiles:
    """The designs on disk, one validated file per key."""

    def __init__(self, directory, sdnative):
        self.directory = directory
        self._sd = sdnative

    def path(self, key):
        return os.path.join(self.directory, "%s-%r-%d.json" % key)

    def load(self, key):
        """The key's design (final), or None when there is no valid file; an invalid one is
        deleted so that the design is rebuilt."""
        path = self.path(key)
        try:
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
        except FileNotFoundError:
            return None
        except (OSError, ValueError) as exc:
            return self._reject(path, exc)
        try:
            if not isinstance(data, dict) or data.get("format") != FORMAT or data.get("version") != VERSION:
                raise ValueError("not a version %d lobe design file" % VERSION)
            if design_key(data["lobe"], data["exponent"], data["degree"]) != key:
                raise ValueError("holds the design of another lobe, exponent or degree")
            nodes = np.array(data["nodes"], dtype=np.float64)
            weights = np.array(data["weights"], dtype=np.float64)
            certify(self._sd, key, nodes, weights)
        except (KeyError, TypeError, ValueError) as exc:
            return self._reject(path, exc)
        return Design(nodes, weights, True)

    def _reject(self, path, why):
        log.warning("lobe design file %s rejected (%s); the design is rebuilt", path, why)
        try:
            os.remove(path)
        except OSError:
            pass
        return None

    def save(self, key, design):
        """Writes the design (atomically: a reader sees the old file or the whole new one). A cache
        that cannot be written only costs a rebuild next time."""
        data = {"format": FORMAT, "version": VERSION, "lobe": key.lobe, "exponent": key.exponent,
                "degree": key.degree, "nodes": design.nodes.tolist(), "weights": design.weights.tolist()}
        try:
            os.makedirs(self.directory, exist_ok=True)
            handle, temporary = tempfile.mkstemp(dir=self.directory, suffix=".tmp")
            with os.fdopen(handle, "w", encoding="utf-8") as f:
                json.dump(data, f)
            os.replace(temporary, self.path(key))
        except OSError as exc:
            log.warning("lobe design not cached in %s: %s", self.directory, exc)

    def keys(self):
        """The keys that have a file (not yet validated)."""
        try:
            names = os.listdir(self.directory)
        except OSError:
            return []
        out = []
        for name in names:
            lobe, _, rest = name.partition("-")
            exponent, _, degree = rest.rpartition("-")
            try:
                key = design_key(lobe, float(exponent), int(degree[:-len(".json")]))
            except ValueError:
                continue
            if os.path.basename(self.path(key)) == name:
                out.append(key)
        return out


def _phong_exponent(key):
    """The key's lobe as a Phong lobe, the family continuation moves in: Lambert's weight
    4 max(0, t) is Phong's (2 sigma + 2) max(0, t)^sigma at sigma = 1."""
    return 1.0 if key.lobe == "lambert" else key.exponent


def _distance(a, b):
    """How far apart two lobes are for continuation: a Phong lobe's width scales as 1/(sigma+1)."""
    return abs(math.log((_phong_exponent(a) + 1.0) / (_phong_exponent(b) + 1.0)))


class LobeDesigns:
    """Lobe designs for the draw: `get` never waits for a build; one worker thread builds what is
    missing, in the order asked (background.py). `generation` counts finished builds (the
    add-on redraws when it changes)."""

    def __init__(self, sdnative, directory):
        self._sd = sdnative
        self.files = DesignFiles(directory, sdnative)
        self._builds = background.Background("sd_lighting lobe designs")   # key -> final Design
        self._lock = threading.Lock()
        self._standins = {}    # key -> Gauss product Design, once asked before the final one was there

    @property
    def generation(self):
        return self._builds.generation

    def get(self, lobe, exponent, degree):
        """The design for the lobe and degree: final from memory or disk, else the Gauss product
        rule while the final one builds (a build that failed leaves the Gauss rule for good)."""
        key = design_key(lobe, exponent, degree)
        design = self._builds.get(key)
        if design is not None:
            return design
        with self._lock:
            standin = self._standins.get(key)
        if standin is not None:   # building, or its build failed
            return standin
        design = self.files.load(key)
        if design is not None:
            self._builds.put(key, design)
            return design
        nodes, weights = self._sd.zonal_design(key.lobe, key.exponent, key.degree, "gauss")
        standin = Design(np.asarray(nodes, dtype=np.float64), np.asarray(weights, dtype=np.float64), False)
        with self._lock:
            self._standins[key] = standin
        self._builds.get(key, lambda: self._build_stored(key))
        return standin

    def pending(self):
        """Keys whose final design is still being built, the one in work first."""
        return self._builds.pending()

    def failures(self):
        """key -> why its build failed (not retried in this session)."""
        return self._builds.failures()

    def wait(self, timeout=None):
        """Waits until nothing is pending (True) or the timeout passes (False)."""
        return self._builds.wait(timeout)

    def close(self):
        """Stops taking work: the build in progress (native, not interruptible) ends in its thread
        and its result is dropped."""
        self._builds.close()

    def _neighbour(self, key):
        """The final design of the same degree whose lobe is nearest, or None."""
        known = self._builds.results()
        candidates = {k for k in known if k.degree == key.degree}
        candidates.update(k for k in self.files.keys() if k.degree == key.degree)
        candidates.discard(key)
        for other in sorted(candidates, key=lambda k: _distance(k, key)):
            design = known.get(other) or self.files.load(other)
            if design is not None:
                return other, design
        return None

    def build(self, key):
        """The key's final design, built now in the calling thread (the worker's step; benchmarks):
        continued from the nearest design of the same degree known in memory or on disk, else
        searched from scratch; certified."""
        neighbour = self._neighbour(key)
        design = self._continue(key, *neighbour) if neighbour is not None else None
        if design is None:
            nodes, weights = self._sd.zonal_design(key.lobe, key.exponent, key.degree)
            design = Design(np.asarray(nodes, dtype=np.float64), np.asarray(weights, dtype=np.float64), True)
        certify(self._sd, key, design.nodes, design.weights)
        return design

    def _continue(self, key, start_key, start):
        """The key's design continued from a neighbour's along the lobes in between (steps
        geometric in sigma + 1), or None where a step fails even when halved."""
        goal = _phong_exponent(key)
        exponent, nodes, weights = _phong_exponent(start_key), start.nodes, start.weights
        longest = math.log(CONTINUATION_STEP)
        step = longest
        while exponent != goal:
            distance = math.log((goal + 1.0) / (exponent + 1.0))
            if abs(distance) <= step:
                target = goal
            else:
                target = (exponent + 1.0) * math.exp(math.copysign(step, distance)) - 1.0
            found = self._sd.zonal_design_continued("phong", target, key.degree, exponent, nodes, weights,
                                                    thin=target == goal)
            if found is None:
                step /= 2.0
                if step < longest / 2 ** CONTINUATION_HALVINGS:
                    return None
                continue
            exponent, (nodes, weights) = target, found
        return Design(np.asarray(nodes, dtype=np.float64), np.asarray(weights, dtype=np.float64), True)

    def _build_stored(self, key):
        """The worker's step: the key's design built (`build`) and stored on disk."""
        design = self.build(key)
        self.files.save(key, design)
        return design
