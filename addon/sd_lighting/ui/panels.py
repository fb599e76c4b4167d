"""The sidebar panel (3D viewport > N > SD Lighting), laid out as Blender's own: a parent panel
(the Bake button, its progress and prediction, the live re-bake's state) with sub-panels for the
Environment, the Material, the Method (with the active object's Overrides and the Prediction
before the bake), the Bake's options, the Live Shading (with its Ringing window) and the Active
Object's bake (with its Automatic Choice and Refinement). Settings use `use_property_split`;
rarely used ones sit in sub-panels that start closed.

Every text fits the sidebar's width: settings have short names, values are drawn in label /
value rows, and sentences (choices, reasons, errors) are wrapped to the region's width.
"""

import os
import re
import textwrap

import bpy

from .. import methods, native
from ..bake import geometry, least_squares
from ..live import drawing, gpu_shading, live_rebake, staleness
from ..plan import analysis, cost
from ..scene import environment, light_sources, materials, ringing
from ..store import baked
from ..store.record import RecordError
from . import operators, prediction

# The sidebar's geometry at UI scale 1, in pixels (measured on Blender 3.4's): the category tabs,
# the panel's margins (each side), an icon; the mean width of a character of the UI font (DejaVu
# Sans / Inter, 11 points; 5.6 on an English sentence), on the wide side so that a line fits.
_TABS, _MARGIN, _ICON, _CHARACTER = 21.0, 16.0, 22.0, 6.0
# Blender's property split: the labels' share of a row.
_SPLIT = 0.4
_UNBROKEN = "\u00a0"     # a space textwrap does not break at
_NUMBER_UNIT = re.compile(r"(\d) (%|s\b|ms\b)")


def _chars(context, inset=0.0):
    """How many characters fit one line of the sidebar (less `inset` pixels at scale 1); None
    where the panel is not drawn in a sidebar (a script drawing it): lines are then not wrapped."""
    region = getattr(context, "region", None)
    if region is None or region.type != 'UI':
        return None
    scale = getattr(context.preferences.system, "ui_scale", 1.0) or 1.0
    return max(12, int((region.width / scale - _TABS - 2 * _MARGIN - inset) / _CHARACTER))


def _text(layout, context, text, icon='NONE', inset=0.0):
    """A sentence as labels, wrapped to the sidebar's width (the first line with the icon, the
    others aligned with it)."""
    if not text:
        return
    has_icon = icon != 'NONE'
    width = _chars(context, inset + (_ICON if has_icon else 0.0))
    # a number stays with its unit
    lines = [line.replace(_UNBROKEN, " ") for line in textwrap.wrap(
        _NUMBER_UNIT.sub("\\1" + _UNBROKEN + "\\2", text), width)] if width else [text]
    col = layout.column(align=True)
    for i, line in enumerate(lines or [text]):
        col.label(text=line, icon=icon if i == 0 else ('BLANK1' if has_icon else 'NONE'))


def _fits_value(context, value, inset=0.0):
    """Whether a value fits the value column of a split row."""
    width = _chars(context, inset)
    return width is None or len(value) <= int((1.0 - _SPLIT) * width)


def _value(layout, context, label, value, inset=0.0):
    """A read-only label / value row, split as Blender splits a property's; a value too long
    for its column is a wrapped "label: value" line instead."""
    if not _fits_value(context, value, inset):
        _text(layout, context, "%s: %s" % (label, value), inset=inset)
        return
    split = layout.split(factor=_SPLIT, align=True)
    left = split.row()
    left.alignment = 'RIGHT'
    left.label(text=label)
    split.label(text=value)


def _method_label(context, method_id, inset=0.0):
    """A method's label, or its short one where the label does not fit a value column."""
    method = methods.BY_ID.get(method_id)
    if method is None:
        return method_id
    return method.label if _fits_value(context, method.label, inset) else method.short_label


class _Sidebar:
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = "SD Lighting"


class _SubPanel(_Sidebar):
    bl_parent_id = "SD_PT_lighting"


def _split(layout):
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


class SD_PT_lighting(_Sidebar, bpy.types.Panel):
    """Bake the selected meshes against the environment and shade them live (the Bake button, the
    bake's progress and predicted time, the live re-bake's state)"""
    bl_label = "SD Lighting"
    bl_idname = "SD_PT_lighting"

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.sd_lighting
        problem = native.error_message()
        if problem:
            box = layout.box()
            box.alert = True
            box.label(text="Native module missing", icon='ERROR')
            _text(box, context, problem, inset=_MARGIN)

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
                col = layout.column()
                col.alert = predicted.needs_confirmation
                _text(col, context, "Bake time: " + predicted.text(),
                      icon='ERROR' if predicted.needs_confirmation else 'TIME')
                if settings.refine:
                    _text(col, context, "+ refinement, up to {:,} vertices in all".format(
                        settings.refine_max_vertices), icon='BLANK1')
            elif problem:
                _text(layout, context, "No bake time prediction: " + problem, icon='ERROR')
            elif prediction.settings_key(context) is not None:
                layout.label(text="Predicting the bake time...", icon='TIME')

        rebake = live_rebake.running()
        if rebake is not None:
            _text(layout, context, "Re-baking %s, %d %%" % (rebake[0], int(100 * rebake[1].fraction)),
                  icon='TIME')
            layout.operator("sd_lighting.cancel_bake", text="Cancel", icon='CANCEL')
        elif settings.live_rebake and live_rebake.message:
            _text(layout, context, live_rebake.message, icon='INFO')
        stale = staleness.stale_names(context.scene)
        if stale:
            col = layout.column()
            col.alert = True
            _text(col, context, staleness.message(stale, settings.live_rebake), icon='ERROR')
        if drawing.last_error:
            col = layout.column()
            col.alert = True
            _text(col, context, drawing.last_error, icon='ERROR')


class SD_PT_lighting_environment(_SubPanel, bpy.types.Panel):
    bl_label = "Environment"
    bl_idname = "SD_PT_lighting_environment"

    def draw(self, context):
        layout = _split(self.layout)
        scene = context.scene
        settings = scene.sd_lighting
        layout.row().prop(settings, "environment_source", text="Source", expand=True)
        if settings.environment_source == 'FILE':
            layout.prop(settings, "environment_path")
        try:
            src = environment.source(scene)
            _text(layout, context, os.path.basename(src.path) if src.description == src.path
                  else src.description, icon='WORLD')
            sources = environment.bright_sources(src, wait=False)
            if sources is None:
                drawing.watch_background()   # the panel is drawn again when they are found
            for i, line in enumerate(light_sources.lines(sources, settings.source_shadows)):
                _text(layout, context, line, icon='LIGHT_SUN' if i == 0 else 'DOT')
            if settings.source_shadows and drawing.errors["sources"]:
                _text(layout, context, "Shaded through SH: " + drawing.errors["sources"], icon='ERROR')
        except Exception as exc:  # a broken world must not break the panel
            _text(layout, context, str(exc), icon='ERROR')
        layout.prop(settings, "environment_rotation")
        if environment.mapping_node(scene) is not None:
            _text(layout, context, "Rotation turns the world's Mapping node", icon='INFO')
        layout.prop(scene.view_settings, "exposure")
        _text(layout, context, "Live shading uses the Standard view transform", icon='INFO')


class SD_PT_lighting_material(_SubPanel, bpy.types.Panel):
    bl_label = "Material"
    bl_idname = "SD_PT_lighting_material"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.sd_lighting
        obj = context.active_object
        layout.prop(settings, "material_source", text="Lobes")
        if settings.material_source == 'PHONG':
            layout.prop(settings, "phong_exponent")
        elif settings.material_source == 'MATERIAL' and obj is not None:
            _text(layout, context, materials.lobes_from_material(obj)[1], icon='MATERIAL')
        if obj is not None:
            for line in materials.albedo_summary(obj):
                _text(layout, context, line, icon='DOT')


class SD_PT_lighting_method(_SubPanel, bpy.types.Panel):
    bl_label = "Method"
    bl_idname = "SD_PT_lighting_method"

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.sd_lighting
        layout.prop(settings, "method", text="")
        col = layout.column(align=True)
        if settings.method == analysis.AUTOMATIC:
            col.prop(settings, "target_error")
            col.prop(settings, "max_automatic_order")
        else:
            col.prop(settings, "automatic_orders")
            if settings.automatic_orders:
                col.prop(settings, "target_error")
                col.prop(settings, "max_automatic_order")
            else:
                col.prop(settings, "light_order")
                if settings.refine:
                    col.prop(settings, "target_error")
            col.prop(settings, "visibility_order")
        col = layout.column(align=True)
        col.prop(settings, "rays")
        col.prop(settings, "seed")


class SD_PT_lighting_overrides(_SubPanel, bpy.types.Panel):
    """The active object's own settings: each ticked one replaces the scene's (or the automatic
    choice) for that object."""
    bl_label = "Object Overrides"
    bl_idname = "SD_PT_lighting_overrides"
    bl_parent_id = "SD_PT_lighting_method"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == 'MESH'

    def draw(self, context):
        layout = _split(self.layout)
        obj = context.active_object
        overrides = obj.sd_lighting
        _text(layout, context, "Overrides for %s" % obj.name, icon='OBJECT_DATA')
        col = layout.column()
        col.prop(overrides, "use_method")
        sub = col.column()
        sub.active = overrides.use_method
        sub.prop(overrides, "method", text="")
        col = layout.column(align=True)
        for name in ("light_order", "visibility_order", "rays"):
            row = col.row(align=True, heading=overrides.bl_rna.properties[name].name)
            row.prop(overrides, "use_" + name, text="")
            sub = row.row(align=True)
            sub.active = getattr(overrides, "use_" + name)
            sub.prop(overrides, name, text="")


class SD_PT_lighting_prediction(_SubPanel, bpy.types.Panel):
    """Before the bake: the automatic mode's choice per selected object, or the chosen method's
    predicted error."""
    bl_label = "Prediction"
    bl_idname = "SD_PT_lighting_prediction"
    bl_parent_id = "SD_PT_lighting_method"

    @classmethod
    def poll(cls, context):
        return operators.active_job is None and bool(prediction.predicted_errors(context))

    def draw(self, context):
        layout = _split(self.layout)
        for name, chosen, error in prediction.predicted_errors(context):
            if chosen.chosen_automatically:
                box = layout.box()
                _text(box, context, "Automatic for %s" % name, icon='AUTO', inset=_MARGIN)
                _draw_choice(box, context, chosen, setting=True, reasons=False, inset=_MARGIN)
            else:
                _text(layout, context, "%s: predicted error %.1f %%" % (name, 100 * error), icon='INFO')


class SD_PT_lighting_reasons(_SubPanel, bpy.types.Panel):
    """Why the automatic mode chose what the Prediction shows, per selected object."""
    bl_label = "Reasons"
    bl_idname = "SD_PT_lighting_reasons"
    bl_parent_id = "SD_PT_lighting_prediction"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        return any(chosen.chosen_automatically for _, chosen, _ in prediction.predicted_errors(context))

    def draw(self, context):
        layout = _split(self.layout)
        for name, chosen, _ in prediction.predicted_errors(context):
            if chosen.chosen_automatically:
                _text(layout, context, name, icon='AUTO')
                _draw_reasons(layout, context, chosen)


class SD_PT_lighting_bake(_SubPanel, bpy.types.Panel):
    bl_label = "Bake"
    bl_idname = "SD_PT_lighting_bake"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.sd_lighting
        col = layout.column()
        col.prop(settings, "refine")
        sub = col.column()
        sub.active = settings.refine
        sub.prop(settings, "refine_max_vertices")
        layout.prop(settings, "least_squares")
        col = layout.column()                       # the texture-space bake and its size
        col.row(heading="Lightmap").prop(settings, "texture_space", text="")
        sub = col.column()
        sub.active = settings.texture_space
        sub.prop(settings, "lightmap_size", text="Size")
        layout.prop(settings, "live_rebake")


class SD_PT_lighting_live(_SubPanel, bpy.types.Panel):
    bl_label = "Live Shading"
    bl_idname = "SD_PT_lighting_live"

    def draw_header(self, context):
        self.layout.prop(context.scene.sd_lighting, "live_shading", text="")

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.sd_lighting
        col = layout.column()
        col.active = settings.live_shading
        col.prop(settings, "per_pixel")
        col.row(heading="World").prop(settings, "world_background", text="Background")
        col.row(heading="Texture").prop(settings, "band_limited_texture", text="Band-Limited")
        col.row(heading="Glossy").prop(settings, "prefiltered_glossy", text="Prefiltered")
        row = col.row(heading="Reflections")
        row.active = settings.prefiltered_glossy
        row.prop(settings, "reflection_rays", text="Traced")
        count = row.row()
        count.active = settings.reflection_rays
        count.prop(settings, "reflection_ray_count")
        if settings.reflection_rays and drawing.errors["rays"]:
            _text(layout, context, "Reflections keep the baked visibility: " + drawing.errors["rays"], icon='ERROR')
        col.row(heading="Sources").prop(settings, "source_shadows", text="Sharp Shadows")
        for line in gpu_shading.lobe_design_status() + environment.ringing_window_status() + environment.prefilter_status():
            _text(layout, context, line, icon='TIME')
        layout.operator("sd_lighting.render_preview", icon='IMAGE_DATA')


class SD_PT_lighting_ringing(_SubPanel, bpy.types.Panel):
    """The window against the ringing of the environment's truncated SH."""
    bl_label = "Ringing"
    bl_idname = "SD_PT_lighting_ringing"
    bl_parent_id = "SD_PT_lighting_live"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        layout = _split(self.layout)
        scene = context.scene
        settings = scene.sd_lighting
        layout.prop(settings, "ringing_window", text="Window")
        if context.active_object is not None:
            try:
                choice = drawing.ringing_choice(scene, context.active_object)
                if choice is not None:
                    _text(layout, context, ringing.describe(choice, settings.ringing_window.lower()))
            except Exception as exc:  # a broken environment must not break the panel
                _text(layout, context, str(exc), icon='ERROR')


class SD_PT_lighting_active(_SubPanel, bpy.types.Panel):
    """What the active object's bake stored."""
    bl_label = "Active Object"
    bl_idname = "SD_PT_lighting_active"

    def draw(self, context):
        layout = _split(self.layout)
        settings = context.scene.sd_lighting
        obj = context.active_object
        if obj is None:
            layout.label(text="No active object")
            return
        try:
            record = baked.record(obj)
        except RecordError as exc:
            col = layout.column()
            col.alert = True
            _text(col, context, "Bake of %s: %s" % (obj.name, exc), icon='ERROR')
            layout.operator("sd_lighting.clear_bake", icon='X')
            return
        if record is None:
            _text(layout, context, "%s: not baked" % obj.name, icon='INFO')
            return
        _text(layout, context, "Bake of %s" % obj.name, icon='CHECKMARK')
        method = methods.BY_ID.get(record.method)
        col = layout.column(align=True)
        _value(col, context, "Method", _method_label(context, record.method))
        _value(col, context, "Material", record.lobes.label)
        _value(col, context, "Orders", "s %d, s' %d" % (record.light_order, record.visibility_order))
        _value(col, context, "Rays", "%d" % record.rays)
        _value(col, context, "Vertices", "%d" % record.vertices)
        _value(col, context, "Floats", "%.4g per vertex" % record.floats_per_vertex)
        _value(col, context, "Bytes", "%.4g per vertex" % record.bytes_per_vertex)
        if record.design_nodes_max is not None:     # the designs' nodes
            _value(col, context, "Nodes", "%.1f per vertex" % record.design_nodes_mean)
            _value(col, context, "Max Nodes", "%d" % record.design_nodes_max)
        _value(col, context, "Bake Time", "%.2f s" % record.seconds)
        if record.faces_doubled:    # bake/sides.py
            _value(col, context, "Both Sides", "%d faces" % record.faces_doubled)
        if record.faces_flipped:
            _value(col, context, "Turned Out", "%d faces" % record.faces_flipped)
        if record.least_squares and method is not None and method.data is not None:
            _value(col, context, "Fit", "least squares" if least_squares.applies(method) else "kept as baked")
            if not least_squares.applies(method):
                _text(layout, context, "Least squares is not for %s's designs" % method.label, icon='INFO')
        if record.has_texels:
            _value(col, context, "Lightmap", "%d x %d" % (record.lightmap, record.lightmap))
            _value(col, context, "Texels", "%d, %.2f s" % (record.lightmap_texels, record.lightmap_seconds))
        elif record.lightmap and method is not None:
            _text(layout, context, "Texture space: not for %s (baked per vertex)" % method.label, icon='INFO')
        warnings = layout.column()
        if settings.live_rebake and method is not None and method.designs_per_vertex:
            _text(warnings, context, "%s builds a design per vertex: each live re-bake takes about "
                  "as long" % method.label, icon='ERROR')
        if staleness.known_stale(obj):
            _text(warnings, context, "The mesh changed since the bake: not shaded, %s"
                  % ("re-baking" if settings.live_rebake else "bake again"), icon='ERROR')
        if baked.placed_elsewhere(obj):
            _text(warnings, context, "Not where it was baked (moved, or a copy): other objects' shadows on "
                  "it are from there: bake again", icon='ERROR')
        if baked.scale_changed(obj):
            _text(warnings, context, "Scale changed since the bake: bake again", icon='ERROR')
        if record.traced and not (settings.reflection_rays and settings.prefiltered_glossy):
            _text(warnings, context, "Chosen for traced reflections, drawn with the bake's visibility: "
                  "bake again", icon='ERROR')
        differences = geometry.render_differences(obj)
        if differences:
            _text(warnings, context, "Cycles renders other geometry (%s): the bake and the preview are "
                  "of the viewport's" % "; ".join(differences), icon='INFO')
        if baked.albedo_texture_unbaked(obj):
            _text(warnings, context, "The image texture needs UVs the bake did not keep: bake again",
                  icon='ERROR')
        layout.operator("sd_lighting.clear_bake", icon='X')


def _active_record(context):
    """The active object's BakeRecord, or None (none, or one that cannot be read)."""
    obj = context.active_object
    try:
        return baked.record(obj) if obj is not None else None
    except RecordError:
        return None


class SD_PT_lighting_choice(_SubPanel, bpy.types.Panel):
    """Why the automatic mode chose the active object's method and orders."""
    bl_label = "Automatic Choice"
    bl_idname = "SD_PT_lighting_choice"
    bl_parent_id = "SD_PT_lighting_active"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        record = _active_record(context)
        return record is not None and record.chosen_automatically

    def draw(self, context):
        _draw_choice(_split(self.layout), context, _active_record(context), setting=False, reasons=True)


class SD_PT_lighting_refinement(_SubPanel, bpy.types.Panel):
    """What the refinement of the active object's bake did."""
    bl_label = "Refinement"
    bl_idname = "SD_PT_lighting_refinement"
    bl_parent_id = "SD_PT_lighting_active"
    bl_options = {'DEFAULT_CLOSED'}

    @classmethod
    def poll(cls, context):
        record = _active_record(context)
        return record is not None and record.refined

    def draw(self, context):
        layout = _split(self.layout)
        record = _active_record(context)
        col = layout.column(align=True)
        if not record.refine_levels:
            _value(col, context, "Vertices", "%d, not split" % record.vertices)
        else:
            _value(col, context, "Vertices", "%d -> %d" % (record.unrefined_vertices, record.vertices))
            _value(col, context, "Levels", "%d" % record.refine_levels)
        _value(col, context, "Time", "%.2f s" % record.refine_seconds)
        _value(col, context, "Target", "%.1f %%" % (100 * record.refine_target))
        _value(col, context, "Error Left", "about %.1f %%" % (100 * record.refine_estimated_left))
        if record.refine_levels:
            _value(col, context, "Worst Edge", "%.1f %%" % (100 * record.refine_worst_left))
        if record.refine_budget_reached:
            col = layout.column()
            col.alert = True
            _text(col, context, "Its share of the budget stopped it", icon='ERROR')


def _draw_choice(layout, context, chosen, setting, reasons, inset=0.0):
    """The automatic mode's choice (a BakeRecord: a bake's, or the prediction's before it; with
    `setting`, its method, orders and rays too; with `reasons`, its reasons)."""
    col = layout.column(align=True)
    if setting:
        _value(col, context, "Method", _method_label(context, chosen.method, inset), inset)
        _value(col, context, "Orders", "s %d, s' %d" % (chosen.light_order, chosen.visibility_order), inset)
        _value(col, context, "Rays", "%d" % chosen.rays, inset)
    _value(col, context, "Error", "%.1f %%" % (100 * (chosen.predicted_error or 0.0)), inset)
    _value(col, context, "Terms", "%d per vertex" % (chosen.frame_terms or 0), inset)
    if chosen.vertices:
        if setting:
            _value(col, context, "Vertices", "%d" % chosen.vertices, inset)
        _value(col, context, "CPU Frame", "%.2f ms" % cost.frame_milliseconds(
            chosen.frame_terms or 0, chosen.vertices), inset)
    if reasons:
        _draw_reasons(layout, context, chosen, inset)


def _draw_reasons(layout, context, chosen, inset=0.0):
    """The automatic mode's reasons for its choice, one paragraph each."""
    for line in (chosen.automatic or "").split("\n"):
        _text(layout, context, line, icon='DOT', inset=inset)


# In the order they are drawn: a parent before its sub-panels.
CLASSES = (SD_PT_lighting, SD_PT_lighting_environment, SD_PT_lighting_material,
           SD_PT_lighting_method, SD_PT_lighting_overrides, SD_PT_lighting_prediction,
           SD_PT_lighting_reasons, SD_PT_lighting_bake, SD_PT_lighting_live, SD_PT_lighting_ringing,
           SD_PT_lighting_active, SD_PT_lighting_choice, SD_PT_lighting_refinement)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
