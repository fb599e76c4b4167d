"""The sidebar panel (3D viewport > N > SD Lighting)."""

import bpy

from .. import methods, native
from ..bake import least_squares
from ..live import drawing, gpu_shading, live_rebake
from ..plan import analysis, cost
from ..scene import environment, materials, ringing
from ..store import baked
from ..store.record import RecordError
from . import operators, prediction


class SD_PT_lighting(bpy.types.Panel):
    bl_label = "SD Lighting"
    bl_idname = "SD_PT_lighting"
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "SD Lighting"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        settings = scene.sd_lighting

        problem = native.error_message()
        if problem:
            box = layout.box()
            box.alert = True
            box.label(text="Native module missing", icon='ERROR')
            box.label(text=problem[:120])

        # Environment
        box = layout.box()
        box.label(text="Environment", icon='WORLD')
        box.row().prop(settings, "environment_source", expand=True)
        if settings.environment_source == 'FILE':
            box.prop(settings, "environment_path")
        try:
            box.label(text=environment.source(scene).description[-60:])
        except Exception as exc:  # a broken world must not break the panel
            box.label(text=str(exc), icon='ERROR')
        mapping = environment.mapping_node(scene)
        col = box.column()
        col.prop(settings, "environment_rotation",
                 text="Rotation (world Mapping node)" if mapping else "Rotation")
        box.prop(scene.view_settings, "exposure")
        box.label(text="Live shading uses the Standard view transform", icon='INFO')

        # Method and orders
        box = layout.box()
        box.label(text="Method", icon='SPHERE')
        box.prop(settings, "method", text="")
        if settings.method == analysis.AUTOMATIC:
            row = box.row(align=True)
            row.prop(settings, "target_error")
            row.prop(settings, "max_automatic_order")
        else:
            box.prop(settings, "automatic_orders")
            if settings.automatic_orders:
                row = box.row(align=True)
                row.prop(settings, "target_error")
                row.prop(settings, "max_automatic_order")
            else:
                box.prop(settings, "light_order")
                if settings.refine:
                    box.prop(settings, "target_error")
            box.prop(settings, "visibility_order")
        row = box.row(align=True)
        row.prop(settings, "rays")
        row.prop(settings, "seed")
        row = box.row(align=True)
        row.prop(settings, "texture_space")
        sub = row.row(align=True)
        sub.enabled = settings.texture_space
        sub.prop(settings, "lightmap_size", text="")
        row = box.row(align=True)
        row.prop(settings, "refine")
        sub = row.row(align=True)
        sub.enabled = settings.refine
        sub.prop(settings, "refine_max_vertices")
        box.prop(settings, "least_squares")
        obj = context.active_object
        if obj is not None and obj.type == 'MESH':
            _draw_overrides(box, obj)

        # Material and method
        box = layout.box()
        box.label(text="Material", icon='MATERIAL')
        box.prop(settings, "material_source", text="")
        if settings.material_source == 'PHONG':
            box.prop(settings, "phong_exponent")
        elif settings.material_source == 'MATERIAL' and context.active_object is not None:
            box.label(text=materials.lobes_from_material(context.active_object)[1][:60])
        if context.active_object is not None:
            for line in materials.albedo_summary(context.active_object):
                box.label(text=line[:100])

        # Bake
        job = operators.active_job
        if job is not None:
            row = layout.row(align=True)
            row.label(text="Baking %d %%" % int(100 * job.fraction), icon='TIME')
            row.operator("sd_lighting.cancel_bake", text="Cancel", icon='CANCEL')
        else:
            layout.operator("sd_lighting.bake", icon='RENDER_STILL')
            predicted = prediction.current(context)
            problem = prediction.error(context)
            if predicted is not None:
                row = layout.row()
                row.alert = predicted.needs_confirmation
                refined = " + refinement, up to %d vertices" % settings.refine_max_vertices
                row.label(text="Predicted bake time: " + predicted.text() + (refined if settings.refine else ""),
                          icon='ERROR' if predicted.needs_confirmation else 'TIME')
            elif problem:
                layout.label(text="No bake time prediction: " + problem[:80], icon='ERROR')
            elif prediction.settings_key(context) is not None:
                layout.label(text="Predicting the bake time...", icon='TIME')
            for name, chosen, error in prediction.predicted_errors(context):
                if chosen.chosen_automatically:
                    _draw_choice(layout.box(), "Automatic for %s (before the bake)" % name, chosen)
                else:
                    layout.label(text="%s: predicted error %.1f %%" % (name, 100 * error), icon='INFO')
        layout.prop(settings, "live_rebake")
        rebake = live_rebake.running()
        if rebake is not None:
            row = layout.row(align=True)
            row.label(text="Re-baking %s, %d %%" % (rebake[0], int(100 * rebake[1].fraction)), icon='TIME')
            row.operator("sd_lighting.cancel_bake", text="Cancel", icon='CANCEL')
        elif settings.live_rebake and live_rebake.message:
            layout.label(text=live_rebake.message[:100], icon='INFO')

        # Live shading
        box = layout.box()
        row = box.row()
        row.prop(settings, "live_shading")
        row.prop(settings, "per_pixel")
        box.prop(settings, "world_background")
        box.prop(settings, "band_limited_texture")
        box.prop(settings, "ringing_window")
        if context.active_object is not None:
            try:
                choice = drawing.ringing_choice(scene, context.active_object)
                if choice is not None:
                    box.label(text=ringing.describe(choice, settings.ringing_window.lower())[:100])
            except Exception as exc:  # a broken environment must not break the panel
                box.label(text=str(exc)[:80], icon='ERROR')
        if drawing.last_error:
            box.label(text=drawing.last_error[:80], icon='ERROR')
        for line in gpu_shading.lobe_design_status() + environment.ringing_window_status():
            box.label(text=line[:100], icon='TIME')
        box.operator("sd_lighting.render_preview", icon='IMAGE_DATA')

        # What the active object's bake stored
        obj = context.active_object
        box = layout.box()
        try:
            record = baked.record(obj) if obj is not None else None
        except RecordError as exc:
            box.label(text="Bake of %s: %s" % (obj.name, exc), icon='ERROR')
            box.operator("sd_lighting.clear_bake", icon='X')
            return
        if record is None:
            box.label(text="Active object: not baked")
            return
        box.label(text="Bake of %s" % obj.name, icon='CHECKMARK')
        method = methods.BY_ID.get(record.method)
        col = box.column(align=True)
        col.label(text="Method: %s" % (method.label if method else record.method))
        col.label(text="Material: %s" % record.lobes.label)
        col.label(text="s = %d, s' = %d, %d rays" % (record.light_order, record.visibility_order, record.rays))
        col.label(text="%d vertices, %d floats = %d bytes per vertex" % (
            record.vertices, record.floats_per_vertex, record.bytes_per_vertex))
        if record.design_nodes_max is not None:
            col.label(text="Design nodes per vertex: %.1f mean, %d max" % (
                record.design_nodes_mean, record.design_nodes_max))
        col.label(text="Baked in %.2f s" % record.seconds)
        if record.least_squares and method is not None and method.data is not None:
            col.label(text="Least squares: fitted to the vertices and face centres"
                      if least_squares.applies(method) else
                      "Least squares: not for %s's designs (kept as baked)" % method.label)
        if record.refined:
            _draw_refinement(col, record)
        if record.has_texels:
            col.label(text="Texture space: %d x %d lightmap, %d texels baked in %.2f s" % (
                record.lightmap, record.lightmap, record.lightmap_texels, record.lightmap_seconds))
        elif record.lightmap and method is not None:
            col.label(text="Texture space: not for %s (baked per vertex)" % method.label, icon='INFO')
        if record.chosen_automatically:
            _draw_choice(box, "Automatic choice", record)
        if settings.live_rebake and method is not None and method.designs_per_vertex:
            col.label(text="%s builds a design per vertex: each live re-bake takes about as long"
                      % method.label, icon='ERROR')
        if baked.scale_changed(obj):
            col.label(text="Scale changed since the bake: bake again", icon='ERROR')
        if baked.albedo_texture_unbaked(obj):
            col.label(text="The image texture needs UVs the bake did not keep: bake again",
                      icon='ERROR')
        box.operator("sd_lighting.clear_bake", icon='X')


def _draw_overrides(layout, obj):
    """The active object's overrides: each ticked one replaces the scene's or automatic setting."""
    overrides = obj.sd_lighting
    col = layout.column(align=True)
    col.label(text="Overrides for %s" % obj.name)
    for name in ("method", "light_order", "visibility_order", "rays"):
        row = col.row(align=True)
        row.prop(overrides, "use_" + name, text="")
        sub = row.row(align=True)
        sub.enabled = getattr(overrides, "use_" + name)
        sub.prop(overrides, name)


def _draw_refinement(layout, record):
    """What the refinement of a bake did."""
    if not record.refine_levels:
        layout.label(text="Refine: interpolation error about %.1f %%, nothing split (%.2f s)" % (
            100 * record.refine_estimated_left, record.refine_seconds))
        return
    layout.label(text="Refined %d -> %d vertices in %d levels (%.2f s)" % (
        record.unrefined_vertices, record.vertices, record.refine_levels, record.refine_seconds))
    row = layout.row()
    row.alert = bool(record.refine_budget_reached)
    row.label(text="Interpolation error left about %.1f %%, largest edge %.1f %% (target %.1f %%)%s" % (
        100 * record.refine_estimated_left, 100 * record.refine_worst_left, 100 * record.refine_target,
        ": Max Vertices stopped it" if record.refine_budget_reached else ""))


def _draw_choice(layout, title, chosen):
    """The automatic mode's choice (a BakeRecord: a bake's, or the prediction's before it) with
    its reasons, one line each."""
    method = methods.BY_ID.get(chosen.method)
    col = layout.column(align=True)
    col.label(text="%s: %s, s = %d, s' = %d, %d rays" % (
        title, method.label if method else chosen.method, chosen.light_order, chosen.visibility_order,
        chosen.rays), icon='AUTO')
    col.label(text="Predicted error %.1f %%, %d frame terms per vertex" % (
        100 * (chosen.predicted_error or 0.0), chosen.frame_terms or 0))
    if chosen.vertices:
        col.label(text="Predicted frame: %.2f ms on the CPU evaluator for %d vertices" % (
            cost.frame_milliseconds(chosen.frame_terms or 0, chosen.vertices), chosen.vertices))
    for line in (chosen.automatic or "").split("\n"):
        col.label(text=line[:100])


CLASSES = (SD_PT_lighting,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
