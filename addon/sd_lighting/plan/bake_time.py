"""The predicted time of a bake, from timed bakes of a few sampled triangles (issue: orders that
cannot be baked in reasonable time are not offered blindly).

A bake costs a setup (the Embree scene of the mesh and its occluders, which faces bound a solid)
plus a time per vertex that depends on the method and orders - MSD (13) builds a design per
vertex, milliseconds at degree 6, tens of seconds at 18 - and on how much of the sky the vertex
sees. The sample: a few triangles drawn at random (seeded) with their own vertices, baked by
sdnative.bake_transfer with the bake's own options against the whole mesh and its occluders, so a
sampled vertex sees what it sees in the bake and the setup is the bake's own, on as many threads.
The bake reports its setup (`setup_seconds`); the rest of a round's time is its vertices' and a
call's fixed cost. A first small round measures the setup; then the largest round whose vertices
the first predicts within SAMPLE_BUDGET (each round builds the scene again, 13 s for a mesh of
millions of triangles); the line through the two separates the vertices' time from the fixed
cost. A refinement before the bake (bake/refine.py) is predicted first, by refining REFINE_SAMPLE
of the copy's triangles (all of a small one), in connected patches of REFINE_PATCH
(refine.Surface.patches), against the rest: its time, and how many vertices the bake will trace
(a low-poly model of 1,140 vertices is refined to 69,271, and its bake took 50 times what its
unrefined vertices predicted). Each object adds TASK_SECONDS of work around its bake.
While a round's rays run, their progress gives a lower bound, so a bake that takes hours says
so within a second of them.

Nothing here needs Blender; the sdnative module is passed in.
"""

import threading
import time
from dataclasses import dataclass

import numpy as np

from ..background import Worker

CONFIRM_SECONDS = 60.0       # a longer bake asks before it starts
RUN = 64                     # consecutive triangles sampled together
# An object's work besides what its sampled bakes measure (its copy, the refinement's and the
# fit's work beyond their bakes, storing): blender_tests/benchmark_large.py --scene many bakes 200 cubes
# of 8 vertices at the defaults in 12.7 s, of which the rounds predicted 2 s.
TASK_SECONDS = 0.05
ROUNDS = (2, 16, 128, 1024)  # triangles per sample round (about 3 vertices each): the first, then one more
# Triangles whose refinement predicts the copy's, in connected patches: the refinement follows
# shadow edges, which a few large patches may miss (README, Use: the predicted bake time).
REFINE_SAMPLE = 2048
REFINE_PATCH = 32
SAMPLE_BUDGET = 5.0          # seconds a further round may take
# A job whose bake is predicted to need more than the free memory over this is not sampled: its
# sample bakes build the scene of the whole mesh, nearly as large as the bake's own, and the memory
# model runs low for an open mesh that bakes a reverse copy of each face (README, Accuracy against
# cost, Scale).
MEMORY_MARGIN = 1.5


def sample_rows(triangle_count, count, seed=0, run=1):
    """The indices of `count` of `triangle_count` triangles (all of them, in order, when that is
    all): runs of `run` consecutive triangles from starts drawn at random without replacement
    (seeded). The timing rounds take runs of RUN:
    a mesh's neighbouring triangles are mostly near in its order, and a bake's rays from
    neighbouring vertices find the scene in the cache that isolated vertices would not (sampled
    one by one, a 2M-vertex mesh's rays took 2.8 times the bake's per vertex); a measurement of
    errors takes them one by one."""
    if count >= triangle_count:
        return np.arange(triangle_count)
    run = max(min(run, count), 1)
    rng = np.random.default_rng(seed)
    starts = run * rng.choice(triangle_count // run, max(count // run, 1), replace=False)
    return (starts[:, None] + np.arange(run)[None, :]).ravel()[:count]


def sample_mesh(vertices, normals, triangles, count, seed=0, run=1):
    """The triangles sample_rows draws and their vertices, re-indexed: (vertices [n, 3],
    normals [n, 3], triangles [count, 3] int32)."""
    triangles = np.asarray(triangles).reshape(-1, 3)
    chosen = triangles[sample_rows(len(triangles), count, seed, run)]
    if len(chosen) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), np.int32)
    used, inverse = np.unique(chosen.ravel(), return_inverse=True)
    return (np.asarray(vertices)[used], np.asarray(normals)[used],
            inverse.reshape(-1, 3).astype(np.int32))


def extrapolate(rounds, vertex_count):
    """Seconds for `vertex_count` vertices from timed rounds [(vertices, setup seconds, seconds)]:
    the setup of the largest round plus the rest of a round's seconds - its vertices' and what a
    call costs besides (threads, results) - as the line through the two largest rounds' gives them,
    or, from one round or a line that falls (noise), its time per vertex."""
    rounds = sorted(rounds)
    n2, setup, seconds2 = rounds[-1]
    net2 = max(seconds2 - setup, 0.0)
    if len(rounds) > 1:
        n1, setup1, seconds1 = rounds[-2]
        per_vertex = (net2 - max(seconds1 - setup1, 0.0)) / (n2 - n1) if n2 > n1 else -1.0
        if per_vertex > 0.0:
            return setup + max(net2 - per_vertex * n2, 0.0) + per_vertex * vertex_count
    return setup + net2 * vertex_count / n2


def lower_bound(elapsed, done, threads, vertex_count):
    """Seconds that `vertex_count` vertices take at least, from rays that ran `elapsed` seconds
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
    a function of (sdnative, a sample bake's result, the growth of the mesh's vertices by its
    refinement) returning the seconds the bake spends after its rays (the least-squares fit),
    called in the worker; `extra_points`: points baked beside the mesh's vertices at the same cost
    per point (texels), a count or a function returning one, called in the worker after the
    keywords; `refinement`: None, or a function of (sdnative, stop) returning None or a
    BakeTask.refinement_estimate of a refinement before the bake, called in the worker after the
    keywords (the traced mesh grows as its triangles do); `memory`: None, or a function returning
    the bake's predicted peak bytes and the name it is told by."""
    mesh: object
    bake_arguments: object
    task: object = None
    after_rays: object = None
    extra_points: object = 0
    refinement: object = None
    memory: object = None

    def points(self):
        return int(self.extra_points() if callable(self.extra_points) else self.extra_points)

    def arguments(self, stop):
        return self.bake_arguments(stop) if callable(self.bake_arguments) else self.bake_arguments

    def traced_mesh(self):
        return self.mesh() if callable(self.mesh) else self.mesh


class BakeTimePredictor(Worker):
    """Times sample bakes of every job in a worker thread (start()); `prediction()` at any time."""

    thread_name = "sd_lighting bake time"

    def __init__(self, sdnative, jobs, threads, available=None):
        """available: None, or a function returning the free bytes (or None where unknown): a job
        that may not fit them is not sampled (MEMORY_MARGIN) and the prediction fails saying so."""
        super().__init__()
        self._available = available
        self._sd = sdnative
        self._jobs = jobs
        self._threads = max(int(threads), 1)
        self._lock = threading.Lock()
        self._estimates = [None] * len(jobs)   # per job: seconds from its finished rounds
        self._running = None                   # (job index, vertices, rays' start or None, done, round vertices)
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
        # a bound only while the round's rays run (its last vertices done, it is finishing: no
        # vertex's time is in the seconds that pass)
        bound = (running is not None and estimates[running[0]] is None and running[2] is not None
                 and running[3] < running[4])
        if bound:
            _, count, start, done, _ = running
            total += lower_bound(time.perf_counter() - start, done, self._threads, count)
        if total == 0.0 and not self.finished:
            return None
        return Prediction(total, self.finished, bound)

    def run(self):
        try:
            for index, job in enumerate(self._jobs):
                self._check_memory(job)
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

    def _check_memory(self, job):
        """Raises MemoryError when the job's bake may not fit the free memory (MEMORY_MARGIN)."""
        free = self._available() if self._available is not None else None
        if job.memory is None or free is None:
            return
        needed, name = job.memory()
        if needed * MEMORY_MARGIN > free:
            raise MemoryError("%s's bake needs about %.1f GB of memory and %.1f GB are free: not sampled, "
                              "its sample bakes would need nearly as much" % (name, needed / 1e9, free / 1e9))

    def _sample(self, index, job):
        arguments = job.arguments(lambda: self.cancel_requested)
        mesh = job.traced_mesh()
        refinement = (job.refinement(self._sd, lambda: self.cancel_requested)
                      if job.refinement is not None else None)
        growth = 1.0 if refinement is None else refinement.triangle_growth
        count = int(round(len(mesh[0]) * growth)) + job.points()
        rounds = []
        sizes = list(ROUNDS[:1])
        while sizes:
            vertices, normals, sample_triangles = sample_mesh(*mesh, sizes.pop(), seed=index, run=RUN)
            start = time.perf_counter()
            with self._lock:
                self._running = (index, count, None, 0, len(vertices))

            def progress(done, total):
                # the rays' start: the first report with the vertex count (before it, the set-up
                # reports (0, 0): no bound yet)
                with self._lock:
                    rays = self._running[2]
                    if rays is None and total > 0:
                        rays = time.perf_counter()
                    self._running = (index, count, rays, done, len(vertices))
                return not self.cancel_requested

            result = self._sd.bake_transfer(vertices, normals, sample_triangles, progress=progress,
                                            **arguments)
            elapsed = time.perf_counter() - start
            # the call's own setup, and the arrays' way into it (the occluders: seconds for millions)
            setup = float(result["setup_seconds"]) + max(elapsed - float(result["seconds"]), 0.0)
            rounds.append((len(vertices), setup, elapsed))
            with self._lock:
                self._estimates[index] = extrapolate(rounds, count) + (0.0 if refinement is None
                                                                       else refinement.seconds)
            if len(rounds) == 1 and len(vertices) < len(mesh[0]):   # the mesh not all sampled yet
                # the second round pays its setup again; its vertices' time is what the budget bounds
                sizes = [size for size in ROUNDS[1:]
                         if extrapolate(rounds, 3 * size) - rounds[0][1] <= SAMPLE_BUDGET][-1:]
        with self._lock:
            self._estimates[index] += TASK_SECONDS
        if job.after_rays is not None:
            after = job.after_rays(self._sd, result, 1.0 if refinement is None else refinement.vertex_growth)
            with self._lock:
                self._estimates[index] += after
