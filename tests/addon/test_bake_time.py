"""The bake-time prediction (plan/bake_time.py): the sample, the extrapolation, the lower bound
while sampling, the text and the confirmation threshold."""

import threading
import time

import numpy as np
import pytest

from sd_lighting.plan import bake_time
from sd_lighting.bake.task import RefinementEstimate
from sd_lighting.plan.bake_time import BakeTimePredictor, Prediction, SampleJob


def grid(n):
    """An n x n vertex grid in the plane z = 0: vertices, normals, triangles."""
    x, y = np.meshgrid(np.arange(n, dtype=np.float64), np.arange(n, dtype=np.float64))
    vertices = np.stack([x.ravel(), y.ravel(), np.zeros(n * n)], axis=1)
    normals = np.tile([0.0, 0.0, 1.0], (n * n, 1))
    i = np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]
    i = i.ravel()
    triangles = np.concatenate([np.stack([i, i + 1, i + n], 1), np.stack([i + 1, i + n + 1, i + n], 1)])
    return vertices, normals, triangles.astype(np.int32)


def test_sample_rows_are_runs_of_distinct_triangles():
    rows = bake_time.sample_rows(1000, 128, seed=1, run=64)
    assert len(rows) == 128 == len(np.unique(rows)) and rows.max() < 1000
    assert np.all(np.diff(rows.reshape(2, 64), axis=1) == 1)   # two runs of consecutive triangles
    assert np.array_equal(bake_time.sample_rows(10, 128, run=64), np.arange(10))   # all of a small mesh
    assert len(bake_time.sample_rows(0, 16)) == 0


def test_sample_mesh_keeps_its_triangles():
    vertices, normals, triangles = grid(20)
    v, n, t = bake_time.sample_mesh(vertices, normals, triangles, 16, seed=3)
    assert t.shape == (16, 3) and t.dtype == np.int32
    assert len(v) == len(n) == len(np.unique(t)) and t.max() == len(v) - 1
    # every sampled triangle is one of the mesh's, with its own corners
    original = {tuple(row) for row in vertices[triangles].reshape(-1, 9).round(9)}
    assert all(tuple(row) in original for row in v[t].reshape(-1, 9).round(9))
    again = bake_time.sample_mesh(vertices, normals, triangles, 16, seed=3)
    assert np.array_equal(again[0], v)   # seeded
    assert len(bake_time.sample_mesh(vertices, normals, triangles[:5], 16)[2]) == 5


def test_extrapolation_adds_the_vertices_to_the_setup():
    # rounds (vertices, the bake's setup seconds, its seconds): the line through the two separates
    # a call's fixed cost (0.1 s) from the vertices' time (0.01 s each)
    rounds = [(6, 0.5, 0.5 + 0.1 + 6 * 0.01), (48, 0.6, 0.6 + 0.1 + 48 * 0.01)]
    assert bake_time.extrapolate(rounds, 10000) == pytest.approx(0.6 + 0.1 + 100.0)
    # a line that falls (noise): the largest round's time per vertex
    assert bake_time.extrapolate([(6, 0.5, 0.9), (48, 0.5, 0.8)], 480) == pytest.approx(0.5 + 3.0)
    # a setup of seconds against a large mesh does not count as vertices' time
    assert bake_time.extrapolate([(6, 5.0, 5.06)], 2_000_000) == pytest.approx(5.0 + 0.01 * 2_000_000)
    assert bake_time.extrapolate([(10, 1.0, 0.9)], 1000) == pytest.approx(1.0)


def test_lower_bound_counts_the_vertices_in_flight():
    # 10 s on 2 threads with nothing finished: each thread is still on its first vertex, so each
    # vertex takes over 10 s of a thread: 1000 vertices take over 5000 s on the two.
    assert bake_time.lower_bound(10.0, 0, 2, 1000) == pytest.approx(5000.0)
    assert bake_time.lower_bound(10.0, 98, 2, 1000) == pytest.approx(100.0)


def test_text_and_confirmation():
    assert Prediction(30.0, True, False).text() == "about 30 s"
    assert Prediction(150.0, True, False).text() == "about 2.5 min"
    assert Prediction(7200.0, False, True).text() == "at least 2.0 h (estimating)"
    assert Prediction(3 * 86400.0, False, False).text() == "about 3.0 days (estimating)"
    assert not Prediction(bake_time.CONFIRM_SECONDS, True, False).needs_confirmation
    assert Prediction(bake_time.CONFIRM_SECONDS + 1.0, True, False).needs_confirmation


class FakeNative:
    """bake_transfer that takes SETUP + PER_VERTEX per vertex (sleeping), with progress as
    sdnative's: (0, 0) during the set-up, then (done, vertex count) from before the first vertex."""
    SETUP, PER_VERTEX = 0.05, 0.004

    def __init__(self):
        self.calls = []
        self.gate = threading.Event()
        self.gate.set()

    def bake_transfer(self, vertices, normals, triangles, progress=None, **kwargs):
        self.calls.append((len(vertices), kwargs))
        start = time.perf_counter()
        if progress is not None:
            progress(0, 0)
        time.sleep(self.SETUP)
        setup = time.perf_counter() - start
        if progress is not None:
            progress(0, len(vertices))
        for done in range(len(vertices)):
            self.gate.wait(30)   # closed: the rays stall in their first vertex
            time.sleep(self.PER_VERTEX)
            if progress is not None and not progress(done + 1, len(vertices)):
                raise RuntimeError("cancelled")
        return {"setup_seconds": setup, "seconds": time.perf_counter() - start}


def test_predictor_recovers_setup_and_per_vertex_time():
    sd = FakeNative()
    vertices, normals, triangles = grid(50)
    predictor = BakeTimePredictor(sd, [SampleJob((vertices, normals, triangles), {"rays": 64})], threads=1)
    predictor.start()
    assert predictor.join(30)
    predicted = predictor.prediction()
    expected = FakeNative.SETUP + FakeNative.PER_VERTEX * len(vertices) + bake_time.TASK_SECONDS
    assert predicted.final and not predicted.lower_bound
    assert predicted.seconds == pytest.approx(expected, rel=0.3)
    # a first round, then the largest one within the budget
    assert [kwargs for _, kwargs in sd.calls] == [{"rays": 64}] * 2
    assert [count for count, _ in sd.calls][1] > [count for count, _ in sd.calls][0]


def test_predictor_sums_objects_and_gives_a_lower_bound_while_sampling():
    sd = FakeNative()
    sd.gate.clear()
    vertices, normals, triangles = grid(30)
    jobs = [SampleJob((vertices, normals, triangles), {}), SampleJob((vertices, normals, triangles), {})]
    predictor = BakeTimePredictor(sd, jobs, threads=1)
    predictor.start()
    time.sleep(0.3)
    bound = predictor.prediction()
    assert bound.lower_bound and not bound.final
    # about 0.25 s since the rays started and the first vertex not done (a degree-16 design takes
    # seconds): each vertex takes over 0.2 s on the one thread
    assert bound.seconds >= 0.2 * len(vertices)
    sd.gate.set()
    assert predictor.join(30)
    total = predictor.prediction()
    assert total.final and not total.lower_bound
    one = FakeNative.SETUP + FakeNative.PER_VERTEX * len(vertices) + bake_time.TASK_SECONDS
    assert total.seconds == pytest.approx(2 * one, rel=0.3)


def test_cancel_stops_sampling():
    sd = FakeNative()
    vertices, normals, triangles = grid(30)
    predictor = BakeTimePredictor(sd, [SampleJob((vertices, normals, triangles), {})], threads=1)
    predictor.cancel()
    predictor.start()
    predictor.join(30)
    assert not predictor.finished and predictor.error is None


def test_a_failing_sample_reports_why():
    class Failing(FakeNative):
        def bake_transfer(self, *args, **kwargs):
            raise ValueError("rays must be in [1, 16777216], got 0")
    vertices, normals, triangles = grid(10)
    predictor = BakeTimePredictor(Failing(), [SampleJob((vertices, normals, triangles), {})], threads=1)
    predictor.start()
    predictor.join(30)
    assert not predictor.finished and "rays must be" in predictor.error


def test_the_mesh_is_made_in_the_worker_after_the_arguments():
    # The corner and centroid splits of a large mesh take a while: not on Blender's main thread,
    # and only once the (automatic) settings that decide them are chosen.
    calls = []
    vertices, normals, triangles = grid(10)

    def arguments(stop):
        calls.append(("arguments", threading.current_thread()))
        return {}

    def mesh():
        calls.append(("mesh", threading.current_thread()))
        return vertices, normals, triangles
    predictor = BakeTimePredictor(FakeNative(), [SampleJob(mesh, arguments)], threads=1)
    assert predictor.prediction() is None and not calls
    predictor.start()
    assert predictor.join(30)
    assert [name for name, _ in calls] == ["arguments", "mesh"]
    assert all(thread is not threading.main_thread() for _, thread in calls)


def test_what_follows_the_rays_is_added_once_from_a_sample_result():
    vertices, normals, triangles = grid(30)
    seen = []

    def after_rays(sd, result, growth):
        seen.append((result, growth))
        return 100.0 * growth
    plain = BakeTimePredictor(FakeNative(), [SampleJob((vertices, normals, triangles), {})], threads=1)
    fitted = BakeTimePredictor(FakeNative(), [SampleJob((vertices, normals, triangles), {}, None, after_rays)],
                               threads=1)
    for predictor in (plain, fitted):
        predictor.start()
        assert predictor.join(30)
    assert len(seen) == 1 and set(seen[0][0]) == {"setup_seconds", "seconds"}   # FakeNative's bake result
    assert seen[0][1] == 1.0   # no refinement: the mesh's own vertices
    assert fitted.prediction().seconds == pytest.approx(plain.prediction().seconds + 100.0, rel=0.2)


def test_extra_points_are_predicted_at_the_vertices_cost():
    vertices, normals, triangles = grid(30)
    plain = BakeTimePredictor(FakeNative(), [SampleJob((vertices, normals, triangles), {})], threads=1)
    texels = BakeTimePredictor(FakeNative(), [SampleJob((vertices, normals, triangles), {},
                                                        extra_points=lambda: 2 * len(vertices))], threads=1)
    for predictor in (plain, texels):
        predictor.start()
        assert predictor.join(30)
    setup = FakeNative.SETUP
    assert texels.prediction().seconds - setup == pytest.approx(3.0 * (plain.prediction().seconds - setup), rel=0.2)


def test_a_refinement_adds_its_time_and_the_points_it_makes():
    # A refinement predicted to take 2 s and to leave 3 times the vertices and 4 times the
    # triangles: the traced mesh grows as the triangles, the fit after the rays as the vertices.
    vertices, normals, triangles = grid(30)
    grown = []

    def after_rays(sd, result, growth):
        grown.append(growth)
        return 0.0
    estimate = RefinementEstimate(2.0, 3.0, 4.0)
    plain = BakeTimePredictor(FakeNative(), [SampleJob((vertices, normals, triangles), {})], threads=1)
    refined = BakeTimePredictor(FakeNative(), [SampleJob((vertices, normals, triangles), {}, None, after_rays,
                                                         refinement=lambda sd, stop: estimate)], threads=1)
    for predictor in (plain, refined):
        predictor.start()
        assert predictor.join(30)
    added = refined.prediction().seconds - plain.prediction().seconds
    assert added == pytest.approx(2.0 + 3 * FakeNative.PER_VERTEX * len(vertices), rel=0.3)
    assert grown == [3.0]


def test_a_job_that_may_not_fit_the_free_memory_is_not_sampled():
    """Its sample bakes would build the whole scene (bake_time.MEMORY_MARGIN): the prediction fails
    saying so, and nothing is baked; with the memory to spare it samples as before."""
    vertices, normals, triangles = grid(10)
    baked = []

    class Counting(FakeNative):
        def bake_transfer(self, *args, **kwargs):
            baked.append(1)
            return super().bake_transfer(*args, **kwargs)

    def job():
        return SampleJob((vertices, normals, triangles), {}, memory=lambda: (int(2e9), "Sheet"))
    short = BakeTimePredictor(Counting(), [job()], threads=1, available=lambda: int(2.9e9))
    short.start()
    short.join(30)
    assert not short.finished and "Sheet's bake needs about 2.0 GB" in short.error and not baked
    roomy = BakeTimePredictor(Counting(), [job()], threads=1, available=lambda: int(3.1e9))
    roomy.start()
    assert roomy.join(30) and baked
