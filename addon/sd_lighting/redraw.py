"""Redrawing Blender's 3D viewports (the one loop over windows, areas and regions) and the status
bar's text."""


def viewports(region_type=None):
    """Tags every 3D viewport of every window for redraw: whole areas (region_type None), or only
    their regions of that type ('WINDOW': the view, 'UI': the sidebar)."""
    import bpy
    for window in getattr(bpy.context.window_manager, "windows", ()):
        for area in window.screen.areas if window.screen is not None else ():
            if area.type != 'VIEW_3D':
                continue
            if region_type is None:
                area.tag_redraw()
                continue
            for region in area.regions:
                if region.type == region_type:
                    region.tag_redraw()


def status_bar(text):
    """Shows the text in the status bar of every window (None: clears it)."""
    import bpy
    for window in getattr(bpy.context.window_manager, "windows", ()):
        with bpy.context.temp_override(window=window):
            workspace = bpy.context.workspace
            if workspace is not None:
                workspace.status_text_set(text)
