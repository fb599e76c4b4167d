"""Live Re-bake (the panel's option, per scene): a baked object whose geometry changes - edit-mode
edits, modifiers - is baked again in the background with the settings its bake recorded, and
the result replaces its bake.

A depsgraph_update_post handler marks the baked objects whose geometry was updated; a timer
drives the state machine of rebake_schedule.py (debounced, one re-bake in flight, a newer
change cancels the running one). A re-bake is the bake's own three steps (bake/): prepare on
the main thread (the evaluated mesh: in edit mode, the edit mesh with its modifiers, as the
viewport shows it: docs/blender-notes.md), BakeJob.run in a worker thread, BakeJob.apply (all or
nothing) on the main thread. An object whose inputs hash as its bake's recorded `inputs` (nothing
the bake depends on changed, e.g. after an undo that brought bake and geometry back together) is
not baked again. A re-bake's result replaces only the bake it started from: one replaced
meanwhile (a bake from the panel, an undo, Clear Bake) is kept. A cancelled or failed re-bake
changes nothing and says so in the status bar - as does every re-bake in Edit Mode of an object
baked with texture-space data, whose unwrap needs Object Mode (bake/unwrap.py): it is baked
again by its next change in Object Mode.

Undo: memfile undo (object mode) restores each baked mesh together with the objects, as of the
undo step - which may predate a re-bake; edit-mode undo restores the edited mesh only. So after
an undo or redo every baked object of the scene is checked as if it had changed; a re-bake
running then is cancelled (its inputs are gone). Nothing here pushes undo steps: a re-bake
follows the geometry, it is not an edit of its own.

The handlers are installed while some scene has the option on (sync), and removed with the
timers when none has, on unregister and when a file is loaded.
"""

import logging
import time

import bpy
from bpy.app.handlers import persistent

from .. import redraw
from ..bake import job, prepare
from ..errors import BakeError
from ..store import baked
from . import drawing
from .rebake_schedule import Scheduler

log = logging.getLogger(__name__)

DELAY = 0.25          # seconds after an object's last change before its re-bake starts
MESSAGE_SECONDS = 5.0  # how long the status bar shows a re-bake's outcome

_scheduler = Scheduler(DELAY)
_bake_from_panel = None   # the BakeJob of a modal bake: no re-bake starts while it runs
message = ""          # the last re-bake's outcome, for the panel and the tests


def enabled(scene):
    settings = getattr(scene, "sd_lighting", None)
    return bool(settings is not None and settings.live_rebake)


def running():
    """(object name, BakeJob) of the re-bake in flight, or None."""
    return _scheduler.running


def pending():
    """Names of the objects waiting for a re-bake."""
    return _scheduler.pending()


# --------------------------------------------------------------------------------------------
# Handlers

def _baked_object(name):
    obj = bpy.data.objects.get((name, None))   # the local one: a library's is never baked
    return obj if baked.baked_mesh(obj) is not None else None


def _mark(names):
    now = time.monotonic()
    for name in names:
        _scheduler.changed(name, now)
    if names and not bpy.app.timers.is_registered(_tick):
        bpy.app.timers.register(_tick, first_interval=DELAY)


@persistent
def _on_depsgraph_update(scene, depsgraph):
    if not enabled(scene):
        return
    names = {update.id.original.name for update in depsgraph.updates
             if update.is_updated_geometry and isinstance(update.id, bpy.types.Object)}
    _mark(sorted(name for name in names if _baked_object(name) is not None))


@persistent
def _on_undo(scene, *_args):
    """undo_post, redo_post: every baked object is checked again (the module's docstring)."""
    drawing.clear_cache()
    if enabled(scene):
        _mark(sorted(obj.name for obj in scene.objects
                     if obj.library is None and baked.baked_mesh(obj) is not None))


HANDLERS = (("depsgraph_update_post", _on_depsgraph_update), ("undo_post", _on_undo),
            ("redo_post", _on_undo))


# --------------------------------------------------------------------------------------------
# The timer

class Rebake(job.BakeJob):
    """A re-bake: a BakeJob that may only replace the bake it started from (`replaces`, its
    bake_id), timed from its prepare (`started`, perf_counter)."""

    def __init__(self, tasks, warnings, replaces, started):
        super().__init__(tasks, warnings)
        self.replaces = replaces
        self.started = started


def _clear_status():
    redraw.status_bar(None)


def _report(text, level=logging.INFO):
    """The outcome of a re-bake: the panel's line, the log, and the status bar for a while."""
    global message
    message = text
    log.log(level, text)
    redraw.status_bar("SD Lighting: " + text)
    if bpy.app.timers.is_registered(_clear_status):
        bpy.app.timers.unregister(_clear_status)
    bpy.app.timers.register(_clear_status, first_interval=MESSAGE_SECONDS)


def _start(name):
    """Starts the object's re-bake (a BakeJob in a worker thread), or returns None when there is
    nothing to bake or it cannot be baked (then says why)."""
    obj = _baked_object(name)
    scene = bpy.context.scene
    if obj is None or scene.objects.get(name) is None:
        return None
    started = time.perf_counter()
    try:
        # the lightmap's unwrap only for a bake that changed (not, e.g., after every undo)
        tasks, warnings = prepare.prepare(bpy.context, [obj], rebake=True, unwrap=False)
        if tasks[0].inputs_hash() == baked.record(obj).inputs:
            return None
        prepare.unwrap_lightmap(bpy.context, tasks[0])
    except BakeError as exc:
        _report("cannot re-bake %s, its bake stays: %s" % (name, exc), logging.WARNING)
        return None
    job = Rebake(tasks, warnings, baked.record(obj).bake_id, started)
    job.start()
    return job


def _show_progress():
    """The running re-bake's progress, in the status bar and the panel."""
    name, job = _scheduler.running
    redraw.status_bar("SD Lighting: re-baking %s, %d %%" % (name, int(100 * job.fraction)))
    redraw.viewports()


def _finish(name, job):
    """Applies a re-bake that ended, or reports why it did not."""
    if job.cancelled:
        _report("re-bake of %s cancelled; its previous bake stays" % name, logging.WARNING)
        return
    if job.error:
        _report("re-bake of %s failed, its previous bake stays: %s" % (name, job.error), logging.WARNING)
        return
    obj = _baked_object(name)
    if obj is None or baked.record(obj).bake_id != job.replaces:
        return      # baked, cleared or undone meanwhile: that bake stays
    try:
        job.apply()
    except Exception as exc:
        _report("re-bake of %s failed while storing it, its previous bake stays: %s" % (name, exc),
                logging.WARNING)
        return
    drawing.clear_cache()
    redraw.viewports()
    _report("re-baked %s (%d vertices) in %.2f s" % (
        name, baked.record(obj).vertices, time.perf_counter() - job.started))


def _tick():
    """The timer: acts on the state machine until it says to wait; None (the timer ends) once
    there is nothing left to do."""
    if _bake_from_panel is not None and not _bake_from_panel.finished:
        return 0.5            # it has the cores; its objects get its result
    while True:
        action = _scheduler.poll(time.monotonic())
        if action is None:
            return None
        if action.kind == "wait":
            if _scheduler.running is not None:
                _show_progress()
            return max(action.seconds, 0.01)
        if action.kind == "start":
            job = _start(action.name)
            if job is not None:
                _scheduler.started(action.name, job)
        elif action.kind == "finished":
            _finish(action.name, action.job)
        redraw.viewports()


# --------------------------------------------------------------------------------------------
# Control

def wait_for(job):
    """A bake from the panel started in the background (after `stop`): no re-bake starts until
    `job` has finished."""
    global _bake_from_panel
    _bake_from_panel = job


def cancel():
    """The user's cancel: stops the running re-bake (reported when it ends), forgets the rest."""
    _scheduler.cancel()


def stop(join_seconds=0.0):
    """Cancels everything and forgets it (a bake from the panel starts, the option is turned off,
    a file is loaded); join_seconds: how long to wait for the running worker to end."""
    job = _scheduler.stop()
    if job is not None and join_seconds:
        job.join(join_seconds)


def sync():
    """Installs the handlers while some scene has the option on; otherwise stops and removes
    them and the timers."""
    on = any(enabled(scene) for scene in bpy.data.scenes)
    for name, handler in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if on and handler not in handlers:
            handlers.append(handler)
        elif not on and handler in handlers:
            handlers.remove(handler)
    if not on:
        _remove(join_seconds=0.0)


def _remove(join_seconds):
    stop(join_seconds)
    for timer in (_tick, _clear_status):
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)


def register():
    # bpy.data is not readable while an add-on registers: the first timer (or load_post) syncs
    bpy.app.timers.register(sync, first_interval=0.0)


def unregister():
    global message, _bake_from_panel
    if bpy.app.timers.is_registered(sync):
        bpy.app.timers.unregister(sync)
    for name, handler in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler in handlers:
            handlers.remove(handler)
    _remove(join_seconds=5.0)
    message, _bake_from_panel = "", None
