"""Stale bakes (issue 32, item 1): a bake is not drawn over geometry it no longer fits.

A bake records a digest of the evaluated mesh it was baked from (store/source.py). Whether an
object's evaluated mesh still has it is checked the next time the object is drawn after something
may have changed it - a depsgraph update of its geometry (an edit in Object or Edit Mode, a
modifier added, changed or applied), a frame change that evaluated it again (shape keys,
armatures, animated modifiers), undo, redo, loading a file - and the verdict is kept until the next
such change: a draw reads one evaluated mesh per changed object, not one per frame.

A bake that does not fit is not drawn: the viewport shows the object in Blender's own shading, a
preview draws it in flat grey and reports it, and the panel and the status bar name it and say to
bake again (with Live Re-bake on, it is being baked again). The same mesh back - an undo, a
modifier removed, the baked frame again - is drawn again. Records from before `source` are
taken as they are.
"""

import bpy
from bpy.app.handlers import persistent

from .. import redraw
from ..bake.geometry import casts
from ..store import baked, source
from ..store.record import RecordError

_verdicts = {}   # object name -> (the bake_id checked, whether it is stale)
_shown = False   # whether the status bar names stale bakes
generation = 0   # counts the depsgraph updates, frame changes, undos and loads seen (drawing's caches)
shape_generation = 0   # counts those that moved or changed what casts shadows (bake/geometry.casts)


def _record(obj):
    try:
        return baked.record(obj)
    except RecordError:
        return None


def stale(obj, depsgraph):
    """Whether the object's bake no longer fits its evaluated mesh in `depsgraph` (an evaluated
    one), checking it when nothing is known since the last change."""
    record = _record(obj)
    if record is None or not record.source:
        return False
    verdict = _verdicts.get(obj.name)
    if verdict is not None and verdict[0] == record.bake_id:
        return verdict[1]
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        current = source.mesh_digest(mesh) if mesh is not None else ""
    finally:
        evaluated.to_mesh_clear()
    is_stale = current != record.source
    _verdicts[obj.name] = (record.bake_id, is_stale)
    if (is_stale or _shown) and not bpy.app.timers.is_registered(_show_status):
        bpy.app.timers.register(_show_status, first_interval=0.0)
    return is_stale


def known_stale(obj):
    """The last verdict on the object's bake, without checking (False while unknown)."""
    record = _record(obj)
    verdict = _verdicts.get(obj.name)
    return bool(record is not None and verdict is not None and verdict[0] == record.bake_id and verdict[1])


def stale_names(scene):
    """The scene's objects whose bakes are known to be stale, sorted."""
    return sorted(obj.name for obj in scene.objects if obj.name in _verdicts and known_stale(obj))


def message(names, live_rebake):
    """What the panel and the status bar say of stale bakes (names: not empty)."""
    listed = ", ".join(names[:3]) + (" and %d more" % (len(names) - 3) if len(names) > 3 else "")
    return "%s changed since %s bake: not shaded, %s" % (
        listed, "its" if len(names) == 1 else "their", "re-baking" if live_rebake else "bake again")


def _show_status():
    """A timer after a check found a stale bake or while one is named: the status bar names the
    scene's stale bakes, or clears once there are none."""
    global _shown
    scene = bpy.context.scene
    names = stale_names(scene) if scene is not None else []
    settings = getattr(scene, "sd_lighting", None)
    redraw.status_bar("SD Lighting: " + message(names, bool(settings and settings.live_rebake)) if names else None)
    redraw.viewports('UI')
    _shown = bool(names)
    return None


def forget(names=None):
    """Drops the verdicts on these objects (None: all): they are checked again when drawn."""
    if names is None:
        _verdicts.clear()
    else:
        for name in names:
            _verdicts.pop(name, None)


@persistent
def _on_update(_scene, depsgraph):
    """depsgraph_update_post, frame_change_post: the objects whose geometry was evaluated again."""
    global generation, shape_generation
    generation += 1
    objects = [update for update in depsgraph.updates if isinstance(update.id, bpy.types.Object)]
    if any((update.is_updated_geometry or update.is_updated_transform) and casts(update.id) for update in objects):
        shape_generation += 1   # not for a camera, a lamp or an empty moved
    forget({update.id.original.name for update in objects if update.is_updated_geometry})


@persistent
def _on_reset(*_args):
    """undo_post, redo_post, load_post: anything may have changed."""
    global generation, shape_generation
    generation += 1
    shape_generation += 1
    forget()


HANDLERS = (("depsgraph_update_post", _on_update), ("frame_change_post", _on_update),
            ("undo_post", _on_reset), ("redo_post", _on_reset), ("load_post", _on_reset))


def register():
    for name, handler in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler not in handlers:
            handlers.append(handler)


def unregister():
    for name, handler in HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if handler in handlers:
            handlers.remove(handler)
    global _shown
    if bpy.app.timers.is_registered(_show_status):
        bpy.app.timers.unregister(_show_status)
    if _shown:
        redraw.status_bar(None)
        _shown = False
    forget()
