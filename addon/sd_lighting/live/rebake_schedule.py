"""When the live re-bake bakes what: the state machine of live_rebake.py, without Blender.

A change to a baked object's geometry marks the object; its re-bake may start `delay` seconds
after its last change (a drag in the viewport is many changes: only its end is baked). One re-bake
runs at a time, the object due first next. A change to the object whose re-bake is running
supersedes that re-bake - its result would show the geometry before the change -: it is
cancelled, its result dropped, and the object re-baked once the cancelled job has ended and the
delay has passed. A cancel (the user's) stops the running re-bake, whose end is still reported,
and forgets the changes not yet baked.

A job is anything with `cancel()` and a `finished` flag (job.BakeJob); time is the caller's
clock, passed in.
"""

from dataclasses import dataclass
from typing import Any, Optional

POLL_INTERVAL = 0.1   # seconds between looks at a running job


@dataclass(frozen=True)
class Action:
    """What the caller does now: "start" the object's re-bake (then `started`), "finished" (the
    job ended: apply, or report its cancel or failure), "superseded" (the job ended after a newer
    change: drop it), or "wait" `seconds` and poll again."""
    kind: str
    name: Optional[str] = None
    job: Any = None
    seconds: float = 0.0


class Scheduler:
    """Debounced re-bakes, at most one in flight."""

    def __init__(self, delay):
        self.delay = float(delay)
        self._due = {}          # object name -> time its re-bake may start
        self.running = None     # (object name, job) of the re-bake in flight
        self._superseded = False

    def changed(self, name, now):
        """The object's geometry changed at `now`."""
        self._due[name] = now + self.delay
        if self.running is not None and self.running[0] == name and not self._superseded:
            self._superseded = True
            self.running[1].cancel()

    def pending(self):
        """Names of the objects waiting for a re-bake."""
        return list(self._due)

    def poll(self, now):
        """The next Action, or None when there is nothing to do (no job, no change)."""
        if self.running is not None:
            name, job = self.running
            if not job.finished:
                return Action("wait", seconds=POLL_INTERVAL)
            self.running = None
            superseded, self._superseded = self._superseded, False
            return Action("superseded" if superseded else "finished", name, job)
        if not self._due:
            return None
        name, due = min(self._due.items(), key=lambda item: item[1])
        if due > now:
            return Action("wait", seconds=due - now)
        del self._due[name]
        return Action("start", name)

    def started(self, name, job):
        """The caller started `job`, the re-bake of `name` that poll asked for."""
        self.running = (name, job)

    def cancel(self):
        """Cancels the running re-bake (poll still reports its end) and forgets pending changes."""
        self._due.clear()
        if self.running is not None:
            self.running[1].cancel()

    def stop(self):
        """Cancels everything and forgets the running job too; returns it (or None) to be joined."""
        self.cancel()
        running, self.running, self._superseded = self.running, None, False
        return running[1] if running is not None else None
