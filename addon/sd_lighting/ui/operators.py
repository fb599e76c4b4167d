"""Operators: bake (sd_lighting.bake), still preview (sd_lighting.render_preview), clear bake."""

import bpy
from bpy.props import BoolProperty, IntProperty, StringProperty

from .. import redraw
from ..bake import prepare
from ..bake.job import BakeJob
from ..errors import BakeError
from ..plan import cost
from ..live import drawing, live_rebake, preview, staleness
from ..store import baked
from . import prediction

active_job = None     # the BakeJob running in the UI, for the panel and poll()


class SD_OT_bake(bpy.types.Operator):
    """Bake the selected meshes against everything visible (Esc cancels)"""
    bl_idname = "sd_lighting.bake"
    bl_label = "Bake"
    bl_options = {'REGISTER', 'UNDO'}

    # Set by invoke when the predicted time asks for the dialog; its OK then runs execute, which
    # starts the modal bake instead of the synchronous one.
    confirmed: BoolProperty(options={'HIDDEN', 'SKIP_SAVE'})
    predicted_time: StringProperty(options={'HIDDEN', 'SKIP_SAVE'})
    predicted_memory: StringProperty(options={'HIDDEN', 'SKIP_SAVE'})
    go_ahead: BoolProperty(name="Go Ahead", description="From a script: bake even when the bake is "
                           "predicted to take over a minute or more memory than is free (the UI asks)",
                           options={'SKIP_SAVE'})

    _timer = None
    _job = None

    @classmethod
    def poll(cls, context):
        if active_job is not None:
            if hasattr(cls, "poll_message_set"):
                cls.poll_message_set("a bake is running")
            return False
        if not any(o.type == 'MESH' for o in context.selected_objects):
            if hasattr(cls, "poll_message_set"):
                cls.poll_message_set("select one or more mesh objects")
            return False
        return True

    def _prepare(self, context):
        chosen = prediction.automatic_choices(context)
        prediction.stop_sampling()
        live_rebake.stop()   # this bake's result replaces what a running re-bake would give
        try:
            tasks, warnings = prepare.prepare(context, context.selected_objects)
        except BakeError as exc:
            self.report({'ERROR'}, "Bake: %s" % exc)
            return None
        for task in tasks:   # what the prediction chose is not measured again
            if task.automatic and task.object_name in chosen:
                task.adopt(*chosen[task.object_name])
        # a confirmed memory figure lets the bake go ahead; a confirmed time alone still has the
        # worker check the memory of the final copy
        return BakeJob(tasks, warnings, go_ahead=self.go_ahead or bool(self.predicted_memory))

    def _finish(self, context, job):
        if job.cancelled:
            self.report({'WARNING'}, "Bake cancelled; nothing was changed")
            return {'CANCELLED'}
        if job.error:
            self.report({'ERROR'}, "Bake failed, nothing was changed: %s" % job.error)
            return {'CANCELLED'}
        try:
            names = job.apply()
        except Exception as exc:
            self.report({'ERROR'}, "Bake failed while storing results, nothing was changed: %s" % exc)
            return {'CANCELLED'}
        drawing.clear_cache()
        for warning in job.warnings:
            self.report({'WARNING'}, "Bake: %s" % warning)
        self.report({'INFO'}, "Baked %s in %.1f s" % (", ".join(names), job.seconds))
        redraw.viewports('WINDOW')
        return {'FINISHED'}

    def execute(self, context):
        """Synchronous bake (scripts and tests): same steps, in the calling thread; after the
        long-bake dialog, the modal bake."""
        if self.confirmed:
            return self._start(context)
        refusal = None if self.go_ahead else prediction.refusal(context)
        if refusal is not None:
            self.report({'ERROR'}, "Bake refused, nothing was changed: %s" % refusal)
            return {'CANCELLED'}
        job = self._prepare(context)
        if job is None:
            return {'CANCELLED'}
        job.run()
        return self._finish(context, job)

    def invoke(self, context, event):
        predicted = prediction.for_confirmation(context)
        memory = prediction.memory(context)
        long = predicted is not None and predicted.needs_confirmation
        large = memory is not None and memory[1] > memory[2]
        if long or large:
            self.confirmed = True
            self.predicted_time = predicted.text() if predicted is not None else ""
            self.predicted_memory = ("%s for %s, %s free" % (cost.memory_text(memory[1]), memory[0],
                                                             cost.memory_text(memory[2])) if large else "")
            return context.window_manager.invoke_props_dialog(self, width=400)
        return self._start(context)

    def draw(self, context):
        if self.confirmed:
            if self.predicted_time:
                self.layout.label(text="Predicted bake time: " + self.predicted_time, icon='ERROR')
            if self.predicted_memory:
                self.layout.label(text="Predicted memory: " + self.predicted_memory, icon='ERROR')
            self.layout.label(text="Bake anyway? (Esc cancels it while it runs)")

    def _start(self, context):
        """The modal bake: a worker thread, progress, Esc."""
        global active_job
        job = self._prepare(context)
        if job is None:
            return {'CANCELLED'}
        wm = context.window_manager
        self._job = job
        active_job = job
        live_rebake.wait_for(job)
        job.start()
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        self._status(context, job.status_text())
        return {'RUNNING_MODAL'}

    def _status(self, context, text):
        workspace = getattr(context, "workspace", None)
        if workspace is not None:
            workspace.status_text_set(text)

    def modal(self, context, event):
        global active_job
        job = self._job
        if event.type == 'ESC':
            if event.value == 'PRESS':
                job.cancel()
                self._status(context, "SD Lighting: cancelling the bake...")
            return {'RUNNING_MODAL'}  # Esc is ours while baking
        if event.type == 'TIMER':
            context.window_manager.progress_update(int(100 * job.fraction))
            if not job.cancel_requested:
                self._status(context, job.status_text())
            redraw.viewports('UI')
            if job.finished:
                wm = context.window_manager
                wm.event_timer_remove(self._timer)
                wm.progress_end()
                self._status(context, None)
                active_job = None
                return self._finish(context, job)
        return {'PASS_THROUGH'}

    def cancel(self, context):
        """Blender ends the operator (e.g. the file is closed): stop the worker, change nothing."""
        global active_job
        if self._job is not None:
            self._job.cancel()
            self._job.join(5.0)
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
        wm.progress_end()
        self._status(context, None)
        active_job = None


class SD_OT_cancel_bake(bpy.types.Operator):
    """Cancel the running bake, or the running live re-bake (its object keeps its bake)"""
    bl_idname = "sd_lighting.cancel_bake"
    bl_label = "Cancel Bake"

    @classmethod
    def poll(cls, context):
        return active_job is not None or live_rebake.running() is not None

    def execute(self, context):
        if active_job is not None:
            active_job.cancel()
        else:
            live_rebake.cancel()
        return {'FINISHED'}


class SD_OT_clear_bake(bpy.types.Operator):
    """Remove the bake of the selected objects (their baked meshes and settings)"""
    bl_idname = "sd_lighting.clear_bake"
    bl_label = "Clear Bake"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return active_job is None and any(baked.baked_mesh(o) for o in context.selected_objects)

    def execute(self, context):
        cleared = []
        for obj in context.selected_objects:
            if baked.baked_mesh(obj) is not None:
                try:
                    baked.clear(obj)
                    cleared.append(obj.name)
                except BakeError as exc:
                    self.report({'WARNING'}, "Clear Bake: %s" % exc)
        drawing.clear_cache()
        if not cleared:
            return {'CANCELLED'}
        baked.remove_unlinked()
        self.report({'INFO'}, "Cleared the bake of %s" % ", ".join(cleared))
        return {'FINISHED'}


class SD_OT_render_preview(bpy.types.Operator):
    """Render what the live shading shows, from the scene camera, to an image file
(.exr: scene-linear; other extensions: 8-bit PNG, Standard view transform)"""
    bl_idname = "sd_lighting.render_preview"
    bl_label = "Render Preview"

    filepath: StringProperty(name="File", subtype='FILE_PATH', default="")
    width: IntProperty(name="Width", default=0, min=0, max=16384,
                       description="Pixels (0: the scene's output resolution)")
    height: IntProperty(name="Height", default=0, min=0, max=16384,
                        description="Pixels (0: the scene's output resolution)")

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.camera is not None

    def _size(self, scene):
        r = scene.render
        scale = r.resolution_percentage / 100.0
        width = self.width or max(1, int(r.resolution_x * scale))
        height = self.height or max(1, int(r.resolution_y * scale))
        return width, height

    def invoke(self, context, event):
        if not self.filepath:
            self.filepath = bpy.path.abspath("//sd_preview.png") if bpy.data.filepath else "sd_preview.png"
            context.window_manager.fileselect_add(self)
            return {'RUNNING_MODAL'}
        return self.execute(context)

    def execute(self, context):
        scene = context.scene
        if not self.filepath:
            self.report({'ERROR'}, "no file path")
            return {'CANCELLED'}
        path = bpy.path.abspath(self.filepath)
        width, height = self._size(scene)
        try:
            image = preview.render(scene, context.evaluated_depsgraph_get(), context.view_layer,
                                   width, height)
            preview.save(path, image, scene.view_settings.exposure)
        except Exception as exc:
            self.report({'ERROR'}, "Preview failed: %s: %s" % (type(exc).__name__, exc))
            return {'CANCELLED'}
        elsewhere = drawing.placed_elsewhere(scene, context.view_layer)
        if elsewhere:
            self.report({'WARNING'}, "Preview: other objects' shadows on %s are from where %s baked: "
                        "bake again where it stands" % (", ".join(elsewhere), "it was" if len(elsewhere) == 1
                                                       else "they were"))
        stale = staleness.stale_names(scene)
        if stale:
            self.report({'WARNING'}, "Preview: %s (drawn grey)" % staleness.message(stale, scene.sd_lighting.live_rebake))
        self.report({'INFO'}, "Preview written to %s" % path)
        return {'FINISHED'}


CLASSES = (SD_OT_bake, SD_OT_cancel_bake, SD_OT_clear_bake, SD_OT_render_preview)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    global active_job
    if active_job is not None:
        active_job.cancel()
        active_job.join(5.0)
        active_job = None
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
