"""Results computed off the main thread (background.py): asking never waits, a result is
computed once and kept, a failure is reported and not raised, waiting callers get the result or
the failure."""

import threading
import time

import pytest

from sd_lighting.background import Background, Busy, Failed, Worker, quiet


class _Held:
    """A computation that returns `value` (or raises `error`) once `release` is set; counts calls."""

    def __init__(self, value=None, error=None):
        self.value, self.error = value, error
        self.release = threading.Event()
        self.calls = 0

    def __call__(self):
        self.calls += 1
        assert self.release.wait(30)
        if self.error is not None:
            raise self.error
        return self.value


def test_get_is_pending_then_the_result():
    work = Background("test")
    compute = _Held(value=42)
    assert work.get("a", compute) is None
    assert work.pending() == ["a"]
    assert work.get("a", compute) is None and work.generation == 0   # asked again meanwhile
    compute.release.set()
    assert work.wait(30)
    assert work.get("a", compute) == 42 and work.get("a") == 42
    assert compute.calls == 1 and work.generation == 1 and work.pending() == []


def test_keys_are_computed_in_the_order_asked():
    work = Background("test")
    order = []
    first = _Held(value=1)
    work.get("first", lambda: order.append("first") or first())
    work.get("second", lambda: order.append("second") or 2)
    assert work.pending() == ["first", "second"]
    first.release.set()
    assert work.wait(30)
    assert order == ["first", "second"] and work.results() == {"first": 1, "second": 2}


def test_a_failure_is_reported_not_raised_nor_retried():
    work = Background("test")
    compute = _Held(error=ValueError("no such lobe"))
    compute.release.set()
    assert work.get("bad", compute) is None
    assert work.wait(30)
    assert work.get("bad", compute) is None and work.pending() == []
    assert work.failures() == {"bad": "ValueError: no such lobe"}
    assert compute.calls == 1 and work.generation == 1
    with pytest.raises(Failed, match="no such lobe"):
        work.result("bad", compute)


def test_result_waits_for_the_computation_in_progress():
    work = Background("test")
    compute = _Held(value="chosen")
    assert work.get("k", compute) is None
    got = []
    waiter = threading.Thread(target=lambda: got.append(work.result("k", compute, timeout=30)))
    waiter.start()
    compute.release.set()
    waiter.join(30)
    assert got == ["chosen"] and compute.calls == 1
    assert work.result("k", compute) == "chosen" and compute.calls == 1   # kept


def test_result_times_out_and_close_ends_waiting():
    work = Background("test")
    compute = _Held(value=1)
    with pytest.raises(TimeoutError):
        work.result("k", compute, timeout=0.05)
    failed = []

    def wait():
        try:
            work.result("k", compute)
        except Failed as exc:
            failed.append(str(exc))

    waiter = threading.Thread(target=wait)
    waiter.start()
    work.close()
    waiter.join(30)
    assert failed == ["test closed"] and work.pending() == []
    compute.release.set()
    assert work.get("k", compute) is None   # the running computation's result is dropped
    assert work.get("other", lambda: 2) is None and work.pending() == []   # nothing new is taken


def test_put_keeps_a_result_without_computing():
    work = Background("test")
    work.put("k", "from a file")
    assert work.get("k", lambda: pytest.fail("computed")) == "from a file" and work.pending() == []


class _Sleeper(Worker):
    """A Worker that runs until `release` is set."""

    thread_name = "test sleeper"

    def __init__(self):
        super().__init__()
        self.release = threading.Event()

    def run(self):
        self.release.wait(30)


def test_quiet_waits_for_the_computation_in_progress_and_starts_none():
    work = Background("test")
    first = _Held(value=1)
    work.get("first", first)
    work.get("second", lambda: 2)
    threading.Timer(0.2, first.release.set).start()
    with quiet(30):
        assert work.results() == {"first": 1}       # waited for: it ended before the block
        work.get("third", lambda: 3)
        time.sleep(0.2)
        assert work.pending() == ["second", "third"] and work.generation == 1   # nothing started
    assert work.wait(30) and work.results() == {"first": 1, "second": 2, "third": 3}


def test_quiet_waits_for_workers_and_says_which_still_runs():
    worker = _Sleeper()
    worker.start()
    work = Background("test")
    with pytest.raises(Busy, match="test sleeper"):
        with quiet(0.2):
            pass
    assert worker.running()
    work.get("after", lambda: 4)            # the Backgrounds were resumed
    assert work.wait(30) and work.get("after") == 4
    threading.Timer(0.2, worker.release.set).start()
    with quiet(30):
        assert not worker.running()
