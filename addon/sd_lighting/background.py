"""Work off the main thread: a Worker runs one job in a thread of its own (a bake, the bake-time
prediction); a Background computes results for the draw, where asking never waits.

Some of what the live shading needs takes longer than a frame - the lobe designs of MSD (12)
(live/lobe_designs.py), the choice of the ringing window (scene/ringing.py). A Background keeps
such results in memory by key; one worker thread computes what is asked, in the order asked, one
at a time. The draw shades with a stand-in until the result is there; `generation` counts the
computations that ended, and a timer redraws the viewports when it changes (drawing.py). A
computation that raises is reported (`failures`) and not retried; it never raises into the draw.
What is not interactive (a preview render, the tests' reference) waits for the result (`result`).

`quiet` holds every such thread out of Python while the main thread calls Blender operators under
a context override: Blender reads the override from C without the GIL when another thread holds it,
and crashes (docs/blender-notes.md, "Long work in the UI").

Nothing here needs Blender.
"""

import contextlib
import logging
import threading
import time
import weakref

log = logging.getLogger(__name__)

_registry_lock = threading.Lock()
_workers = weakref.WeakSet()       # every Worker started
_backgrounds = weakref.WeakSet()   # every Background


class Busy(Exception):
    """A thread of ours was still running when `quiet` had to go on."""


@contextlib.contextmanager
def quiet(timeout):
    """Within the block no thread of this module's runs: it waits up to `timeout` seconds for the
    Workers to end (the caller cancels those it may) and for each Background's computation in
    progress, and starts none until the block ends. Raises Busy, naming what still runs, when
    the time is up."""
    deadline = time.monotonic() + timeout
    with _registry_lock:
        workers, backgrounds = list(_workers), list(_backgrounds)
    for work in backgrounds:
        work._pause()
    try:
        for worker in workers:
            worker.join(max(deadline - time.monotonic(), 0.0))
            if worker.running():
                raise Busy("%s still runs after %g s" % (worker.thread_name, timeout))
        for work in backgrounds:
            if not work._wait_paused(max(deadline - time.monotonic(), 0.0)):
                raise Busy("%s still computes after %g s" % (work.name, timeout))
        yield
    finally:
        for work in backgrounds:
            work._resume()


class Worker:
    """Work of its own (`run`, defined by the subclass) in one daemon thread, cancellable: `run`
    reads `cancel_requested`, which `cancel` sets; `join` waits for the thread."""

    thread_name = "sd_lighting"

    def __init__(self):
        self.cancel_requested = False
        self._thread = None

    def start(self):
        """Runs `run` in a new thread."""
        self._thread = threading.Thread(target=self.run, name=self.thread_name, daemon=True)
        with _registry_lock:
            _workers.add(self)
        self._thread.start()

    def running(self):
        return self._thread is not None and self._thread.is_alive()

    def cancel(self):
        self.cancel_requested = True

    def join(self, timeout=None):
        if self._thread is not None:
            self._thread.join(timeout)

    def run(self):
        raise NotImplementedError


class Failed(Exception):
    """A background computation raised, or its Background was closed before it ended."""


class Background:
    """Results by key, each computed once by one worker thread (`name` names it in the log)."""

    def __init__(self, name):
        self.name = name
        self._lock = threading.Lock()
        self._ended = threading.Condition(self._lock)
        self._results = {}     # key -> result (never None)
        self._queue = []       # (key, compute) to do; the first is being computed
        self._failed = {}      # key -> why its computation failed
        self._thread = None
        self._closed = False
        self._paused = 0       # quiet() blocks open: no computation starts
        self.generation = 0
        with _registry_lock:
            _backgrounds.add(self)

    def get(self, key, compute=None):
        """The key's result, or None while it is not there. With `compute` (a callable of no
        arguments returning the result, not None; run in the worker thread), a key that is neither
        there, queued nor failed is queued."""
        with self._lock:
            if key in self._results:
                return self._results[key]
            if compute is not None:
                self._enqueue(key, compute)
        return None

    def result(self, key, compute, timeout=None):
        """The key's result, waiting for it (queued with `compute` as in `get`) - for callers that
        are not the interactive draw. Raises Failed when its computation failed or the Background
        is closed, TimeoutError after `timeout` seconds."""
        with self._lock:
            self._enqueue(key, compute)
            if not self._ended.wait_for(lambda: key in self._results or key in self._failed or self._closed,
                                        timeout):
                raise TimeoutError("%s: %r not ready after %s s" % (self.name, key, timeout))
            if key in self._results:
                return self._results[key]
            raise Failed(self._failed.get(key, "%s closed" % self.name))

    def put(self, key, result):
        """Keeps a result found without computing it (e.g. read from a file)."""
        with self._lock:
            self._results[key] = result

    def results(self):
        """key -> result, of every result there."""
        with self._lock:
            return dict(self._results)

    def pending(self):
        """Keys queued, the one being computed first."""
        with self._lock:
            return [key for key, _ in self._queue]

    def failures(self):
        """key -> why its computation failed."""
        with self._lock:
            return dict(self._failed)

    def wait(self, timeout=None):
        """Waits until nothing is pending (True) or the timeout passes (False)."""
        with self._lock:
            return self._ended.wait_for(lambda: not self._queue, timeout)

    def close(self):
        """Stops taking work: the computation in progress (native, not interruptible) ends in its
        thread and its result is dropped."""
        with self._lock:
            self._closed = True
            self._queue.clear()
            self._ended.notify_all()

    def _enqueue(self, key, compute):
        """Queues the key unless it is there, queued, failed or the Background closed (lock held)."""
        if (key in self._results or key in self._failed or self._closed
                or any(queued == key for queued, _ in self._queue)):
            return
        self._queue.append((key, compute))
        self._start_thread()

    def _start_thread(self):
        """Starts the worker thread if there is work and none runs (lock held)."""
        if self._thread is None and self._queue and not self._paused and not self._closed:
            self._thread = threading.Thread(target=self._work, name=self.name, daemon=True)
            self._thread.start()

    def _pause(self):
        with self._lock:
            self._paused += 1

    def _wait_paused(self, timeout):
        """Waits until the worker thread has ended (paused: none starts); whether it has."""
        with self._lock:
            return self._ended.wait_for(lambda: self._thread is None, timeout)

    def _resume(self):
        with self._lock:
            self._paused -= 1
            self._start_thread()

    def _work(self):
        while True:
            with self._lock:
                if self._closed or not self._queue or self._paused:
                    self._thread = None
                    self._ended.notify_all()
                    return
                key, compute = self._queue[0]
            result, failure = None, None
            try:
                result = compute()
            except Exception as exc:  # reported by failures(), never raised into the draw
                failure = "%s: %s" % (type(exc).__name__, exc)
                log.error("%s, %s: %s", self.name, key, failure)
            with self._lock:
                if self._closed:
                    self._thread = None
                    self._ended.notify_all()
                    return
                self._queue.pop(0)
                if failure is None:
                    self._results[key] = result
                else:
                    self._failed[key] = failure
                self.generation += 1
                self._ended.notify_all()
