"""The predicted time of a bake, from timed bakes of a few sampled triangles (issue: orders that
cannot be baked in reasonable time are not offered blindly).

A bake costs a setup (the Embree scene of the mesh and its occluders) plus a time per vertex that
depends on the method and orders - MSD (13) builds a design per vertex, milliseconds at degree 6,
tens of seconds at 18 - and on how much of the sky the vertex sees. The sample: a few triangles
drawn at random (seeded) with their own vertices, baked by sdnative.bake_transfer with the bake's
own options against the whole mesh and its occluders, so a sampled vertex sees what it sees in
the bake, on as many threads. Rounds of increasing size separate the setup from the per-vertex
time; a round is skipped when the previous one predicts it would take over SAMPLE_BUDGET. While a
round runs, its progress gives a lower bound, so a bake that takes hours says so within a second.

Nothing here needs Blender; the sdnative module is passed in.
"""

import threading
import time
from dataclasses import dataclass

import numpy as np

from ..background import Worker

CONFIRM_SECONDS = 60.0       # a longer bake asks before it starts
ROUNDS = (2, 16)             # triangles per sample round (about 3 vertices each)
SAMPLE_BUDGET = 5.0          # seconds a further round may take


def sample_mesh(vertices, normals, triangles, count, seed=0):
    """`count` triangles drawn without replacement and their vertices, re-indexed:
    (vertices [n, 3], normals [n, 3], triangles [count, 3] int32)."""
    triangles = np.asarray(triangles).reshape(-1, 3)
    rng = np.random.default_rng(seed)
    chosen = triangles[rng.choice(len(triangles), min(count, len(triangles)), replace=False)]
    used, inverse = np.unique(chosen.ravel(), return_inverse=True)
    return (np.asarray(vertices)[used], np.asarray(normals)[used],
            inverse.reshape(-1, 3).astype(np.int32))


def extrapolate(rounds, vertex_count):
    """Seconds for `vertex_count` vertices from timed rounds [(vertices, seconds)]: the line through
    the two largest rounds (setup + time per vertex), or through the origin from the largest when
    there is one round or the line's setup comes out negative (noise)."""
    rounds = sorted(rounds)
    n2, t2 = rounds[-1]
    if len(rounds) > 1:
        n1, t1 = rounds[-2]
        if n2 > n1:
            per_vertex = (t2 - t1) / (n2 - n1)
            setup = t1 - per_vertex * n1
            if per_vertex > 0.0 and setup >= 0.0:
                return setup + per_vertex * vertex_count
    return t2 * vertex_count / n2


def lower_bound(elapsed, done, threads, vertex_count):
    """Seconds that `vertex_count` vertices take at least, from a round that ran `elapsed` seconds
    and finished `done` vertices on `threads` threads: the threads' time went into those vertices
    and at most one more each."""
    return elapsed * vertex_count / (done + threads)


def format_duration(seconds):
    if seconds < 60.0:
        return "%.0f s" % max(seconds, 1.0)
    if seconds < 3600.0:
        return "%.1f min" % (seconds / 60.0)
    if seconds < 86400.0:
        return "%.1f h" % (seconds / 3600.0)
    return "%.1f days" % (seconds / 86400.0)


@dataclass(frozen=True)
class Prediction:
    seconds: float
    final: bool          # False: still sampling (a lower bound, or an estimate being refined)
    lower_bound: bool    # the seconds are a lower bound (no round finished yet)

    @property
    def needs_confirmation(self):
        return self.seconds > CONFIRM_SECONDS

    def text(self):
        if self.lower_bound:
            return "at least %s (estimating)" % format_duration(self.seconds)
        return "about %s%s" % (format_duration(self.seconds), "" if self.final else " (estimating)")


@dataclass
class SampleJob:
    """One object's bake: the mesh it traces, (vertices, normals, triangles) or a function
    returning them; and bake_transfer's keywords (orders, rays, occluders: every other object's
    triangles), a dict or a function of a stop query returning one. Both functions are called in
    the worker, the keywords first (the automatic mode chooses the settings there, and they
    decide the mesh: least squares' centroid split); `task`: the caller's; `after_rays`: None, or
    a function of (sdnative, a sample bake's result) returning the seconds the bake spends after
    its rays (the least-squares fit), called in the worker; `extra_points`: points baked beside
    the mesh's vertices at the same cost per point (texels), a count or a function returning one,
    called in the worker after the keywords."""
    mesh: object
    bake_arguments: object
    task: object = None
    after_rays: object = None
    extra_points: object = 0

    def points(self):
        return int(self.extra_points() if callable(self.extra_points) else self.extra_points)

    def arguments(self, stop):
        return self.bake_arguments(stop) if callable(self.bake_arguments) else self.bake_arguments

    def traced_mesh(self):
        return self.mesh() if callable(self.mesh) else self.mesh


class BakeTimePredictor(Worker):
    """Times sample bakes of every job in a worker thread (start()); `prediction()` at any time."""

    thread_name = "sd_lighting bake time"

    def __init__(self, sdnative, jobs, threads):
        super().__init__()
        self._sd = sdnative
        self._jobs = jobs
        self._threads = max(int(threads), 1)
        self._lock = threading.Lock()
        self._estimates = [None] * len(jobs)   # per job: seconds from its finished rounds
        self._running = None                   # (job index, vertices, round start, done, round vertices)
        self.finished = False
        self.error = None

    def join(self, timeout=None):
        """Waits for the sampling; whether it finished."""
        super().join(timeout)
        return self.finished

    def prediction(self):
        """The prediction so far: None before anything is known."""
        with self._lock:
            estimates = list(self._estimates)
            running = self._running
        total = sum(e for e in estimates if e is not None)
        bound = running is not None and estimates[running[0]] is None
        if bound:
            _, count, start, done, _ = running
            total += lower_bound(time.perf_counter() - start, done, self._threads, count)
        if total == 0.0 and not self.finished:
            return None
        return Prediction(total, self.finished, bound)

    def run(self):
        try:
            for index, job in enumerate(self._jobs):
                self._sample(index, job)
        except Exception as exc:  # the panel shows it; the bake itself reports its own errors
            if not self.cancel_requested:
                self.error = "%s: %s" % (type(exc).__name__, exc)
        finally:
            with self._lock:
                self._running = None
            self.finished = not self.cancel_requested and self.error is None

    @property
    def jobs(self):
        return self._jobs

    def _sample(self, index, job):
        arguments = job.arguments(lambda: self.cancel_requested)
        mesh = job.traced_mesh()
        count = len(mesh[0]) + job.points()
        rounds = []
        for triangles in ROUNDS:
            vertices, normals, sample_triangles = sample_mesh(*mesh, triangles, seed=index)
            if rounds and extrapolate(rounds, len(vertices)) > SAMPLE_BUDGET:
                break
            start = time.perf_counter()
            with self._lock:
                self._running = (index, count, start, 0, len(vertices))

            def progress(done, total, start=start):
                with self._lock:
                    self._running = (index, count, start, done, total)
                return not self.cancel_requested

            result = self._sd.bake_transfer(vertices, normals, sample_triangles, progress=progress,
                                            **arguments)
            rounds.append((len(vertices), time.perf_counter() - start))
            with self._lock:
                self._estimates[index] = extrapolate(rounds, count)
            if len(vertices) == len(mesh[0]):   # the whole mesh sampled
                break
        if job.after_rays is not None:
            after = job.after_rays(self._sd, result)
            with self._lock:
                self._estimates[index] += after
