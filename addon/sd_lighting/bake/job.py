"""The bake job: BakeTasks run in a worker thread (or the caller's), with progress and
cancellation, then stored all or nothing on the main thread (store/baked.py)."""

import time

from .. import native
from ..background import Worker
from ..errors import BakeError
from ..plan import cost
from ..store import baked
from .task import SharedChoices, share


CHOICE_SHARE = 0.1   # of an automatic task's progress: the choice's measurement


def memory_refusal(name, needed, free):
    """The message of a bake refused for its memory."""
    return ("%s: the bake needs about %s of memory and %s are free: bake fewer or smaller objects, with "
            "a lower vertex budget, order or without Least Squares (from a script: go_ahead=True bakes "
            "anyway)" % (name, cost.memory_text(needed), cost.memory_text(free)))


class BakeJob(Worker):
    """Bakes a list of BakeTasks; run() in any thread (start(): a worker thread), apply() on the
    main thread afterwards."""

    thread_name = "sd_lighting bake"

    def __init__(self, tasks, warnings=(), go_ahead=False):
        super().__init__()
        self.tasks = tasks
        self.go_ahead = go_ahead      # bake even where the memory predicted is over the free memory
        self.warnings = list(warnings)   # for the user, with the result (prepare's, run's)
        self.current = 0              # index of the task being baked
        self.fraction = 0.0           # overall progress in [0, 1]
        self.choosing = False         # the automatic mode is measuring the current object
        self.refining = False         # the current object's copy is being refined
        self.cancelled = False
        self.error = None             # message when the bake failed
        self.finished = False
        self.seconds = 0.0
        self._step_start = time.perf_counter()   # of the current step: the seconds in the status

    def _step(self, choosing=False, refining=False):
        self.choosing, self.refining = choosing, refining
        self._step_start = time.perf_counter()

    def status_text(self):
        """The step, the object, the progress and the step's seconds so far (which move while a
        step's setup - a large mesh's scene - moves no fraction)."""
        if not self.tasks:
            return ""
        task = self.tasks[min(self.current, len(self.tasks) - 1)]
        doing = ("choosing the settings of" if self.choosing else
                 "refining" if self.refining else "baking")
        return "SD Lighting: %s %s (%d/%d), %d %%, %d s  -  Esc to cancel" % (
            doing, task.object_name, min(self.current + 1, len(self.tasks)), len(self.tasks),
            int(100 * self.fraction), time.perf_counter() - self._step_start)

    # -- work
    def run(self):
        sd = None
        start = time.perf_counter()
        try:
            sd = native.get()
            count = len(self.tasks)
            choices = SharedChoices()
            for index, task in enumerate(self.tasks):
                self.current = index
                self._step()
                if self.cancel_requested:
                    raise sd.BakeCancelled("cancelled")

                def task_progress(done, total, index=index):
                    self.fraction = (index + (done / total if total else 0.0)) / count
                    return not self.cancel_requested

                self.check_memory(task)
                # The automatic choice takes the first CHOICE_SHARE of the task's bar, when it runs;
                # the refinement the rest of the first half, when it runs.
                chosen = CHOICE_SHARE if task.automatic else 0.0
                if task.automatic:
                    self._step(choosing=True)
                    choices.choose(task, lambda: self.cancel_requested,
                                   lambda fraction, progress=task_progress: progress(chosen * fraction, 1.0))
                halfway = 0.5 if task.refines else chosen
                t0 = time.perf_counter()
                self._step(refining=True)
                task.refine(sd, share(task_progress, chosen, halfway))
                self._step()
                task.refine_seconds = time.perf_counter() - t0
                self.check_memory(task)   # now of the copy to bake, with its method
                t0 = time.perf_counter()
                result = task.bake(sd, share(task_progress, halfway, 1.0))
                result["seconds"] = time.perf_counter() - t0   # the least-squares fit included
                task.result = result
                if "least_squares_skipped" in result:
                    self.warnings.append("%s: least squares skipped, the vertices keep their baked "
                                         "values (%s)" % (task.object_name, result["least_squares_skipped"]))
                fallbacks = len(result["fallback_normals"])
                if fallbacks:
                    self.warnings.append("%d %s of %s had no usable normal; their faces' normal "
                                         "was used" % (fallbacks, "vertex" if fallbacks == 1 else "vertices",
                                                       task.object_name))
            self.fraction = 1.0
        except Exception as exc:
            if sd is not None and isinstance(exc, getattr(sd, "BakeCancelled", ())):
                self.cancelled = True
            elif self.cancel_requested:
                self.cancelled = True
            else:
                self.error = str(exc) if isinstance(exc, BakeError) else "%s: %s" % (type(exc).__name__, exc)
        finally:
            self.seconds = time.perf_counter() - start
            self.finished = True

    def check_memory(self, task):
        """Raises BakeError when the task's bake is predicted to need more memory than is free
        (unless go_ahead)."""
        free = cost.available_bytes()
        needed = task.predicted_bytes()
        if not self.go_ahead and free is not None and needed > free:
            raise BakeError(memory_refusal(task.object_name, needed, free))

    # -- step 3
    def apply(self):
        """Stores the results (main thread, store/baked.store: all or nothing). Returns the baked
        objects' names."""
        if not self.finished or self.cancelled or self.error:
            raise BakeError("nothing to apply")
        return baked.store([baked.Bake(task.object_name, task.baked, task.result, task.record())
                            for task in self.tasks])
