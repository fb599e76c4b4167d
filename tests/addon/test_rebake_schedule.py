"""The live re-bake's state machine (live/rebake_schedule.py): debounced starts, one re-bake in
flight, a newer change supersedes the running re-bake, a cancel stops it and forgets the rest."""

import pytest

from sd_lighting.live.rebake_schedule import POLL_INTERVAL, Scheduler

DELAY = 0.25


class FakeJob:
    def __init__(self):
        self.finished = False
        self.cancelled = False

    def cancel(self):
        self.cancelled = True


def start(scheduler, now, name):
    """Polls at `now`, expects the start of `name`'s re-bake and starts a FakeJob for it."""
    action = scheduler.poll(now)
    assert (action.kind, action.name) == ("start", name)
    job = FakeJob()
    scheduler.started(name, job)
    return job


def test_idle_without_changes():
    assert Scheduler(DELAY).poll(0.0) is None


def test_debounced_start_after_the_last_change():
    scheduler = Scheduler(DELAY)
    scheduler.changed("Ball", 0.0)
    scheduler.changed("Ball", 0.2)            # a drag: many changes
    action = scheduler.poll(0.3)
    assert action.kind == "wait" and action.seconds == pytest.approx(0.15)
    start(scheduler, 0.45, "Ball")
    assert scheduler.pending() == []


def test_one_in_flight_others_wait():
    scheduler = Scheduler(DELAY)
    scheduler.changed("A", 0.0)
    scheduler.changed("B", 0.1)
    job = start(scheduler, 1.0, "A")
    action = scheduler.poll(2.0)
    assert action.kind == "wait" and action.seconds == POLL_INTERVAL
    assert not job.cancelled                   # another object's change does not cancel it
    job.finished = True
    action = scheduler.poll(2.1)
    assert (action.kind, action.name, action.job) == ("finished", "A", job)
    start(scheduler, 2.1, "B")
    scheduler.running[1].finished = True
    assert scheduler.poll(2.2).kind == "finished"
    assert scheduler.poll(2.2) is None


def test_change_supersedes_the_running_rebake():
    scheduler = Scheduler(DELAY)
    scheduler.changed("Ball", 0.0)
    first = start(scheduler, 0.3, "Ball")
    scheduler.changed("Ball", 0.5)
    assert first.cancelled
    assert scheduler.poll(0.6).kind == "wait"  # the cancelled job has not ended yet
    first.finished = True
    action = scheduler.poll(0.7)
    assert (action.kind, action.job) == ("superseded", first)
    assert scheduler.poll(0.7).kind == "wait"  # the delay after the change has not passed
    second = start(scheduler, 0.8, "Ball")
    second.finished = True
    assert scheduler.poll(0.9).kind == "finished"


def test_cancel_reports_the_end_and_forgets_pending():
    scheduler = Scheduler(DELAY)
    scheduler.changed("A", 0.0)
    scheduler.changed("B", 0.0)
    job = start(scheduler, 0.3, "A")
    scheduler.cancel()
    assert job.cancelled and scheduler.pending() == []
    job.finished = True
    assert scheduler.poll(0.4).kind == "finished"   # the caller reports the cancel
    assert scheduler.poll(0.4) is None


def test_stop_forgets_everything():
    scheduler = Scheduler(DELAY)
    scheduler.changed("A", 0.0)
    job = start(scheduler, 0.3, "A")
    scheduler.changed("A", 0.4)
    scheduler.changed("B", 0.4)
    assert scheduler.stop() is job and job.cancelled
    assert scheduler.running is None and scheduler.poll(10.0) is None
    assert scheduler.stop() is None
