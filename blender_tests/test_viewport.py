"""The add-on in a running Blender UI (under Xvfb): the modal bake runs in a worker thread with
progress while the UI keeps running, cancels on request leaving everything as it was, and the
live shading's POST_VIEW handler draws the baked objects in the viewport with the values of the
CPU evaluator for the viewport's own camera (read back from the viewport's framebuffer), and the
sidebar on the SD Lighting tab, at Blender's default width, fits every text of the panels.
--screenshots (for review; not in the suite, where the pages took half the test's time): the
sidebar with a baked object active is saved under --out: panel.png (the panels as they first
open; panel_2.png... further down) and panel_open.png... (every sub-panel open).
Run: xvfb-run -a blender --factory-startup --enable-event-simulate --python-exit-code 1 \
         --python blender_tests/test_viewport.py -- --zip Z [--out DIR --screenshots]
(--enable-event-simulate lets the test press Esc; without it, it cancels with the Cancel button.)
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

TIMEOUT = 240.0


def unoccluded(scene, depsgraph, eye, points):
    """Points the eye sees (Blender's scene ray cast finds nothing in front of them)."""
    from mathutils import Vector
    out = np.zeros(len(points), dtype=bool)
    for i, point in enumerate(points):
        direction = Vector(point) - Vector(eye)
        hit = scene.ray_cast(depsgraph, Vector(eye), direction.normalized(), distance=direction.length - 1e-3)
        out[i] = not hit[0]
    return out


def boundary_vertices(triangles, count):
    """Vertices on the mesh's border (their pixels mix in the background)."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]]), axis=1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    out = np.zeros(count, dtype=bool)
    out[unique[counts == 1].ravel()] = True
    return out


class Test:
    def __init__(self):
        self.checks = sdtest.Checks("test_viewport")
        self.args = sdtest.arguments()
        self.screenshots = "--screenshots" in sys.argv
        self.package = sdtest.install_addon(self.args.zip)
        self.steps = self.run()
        self.ticks = 0
        self.samples = None
        self.start = None

    # -- helpers
    def viewport(self):
        window = bpy.context.window_manager.windows[0]
        area = next(a for a in window.screen.areas if a.type == 'VIEW_3D')
        region = next(r for r in area.regions if r.type == 'WINDOW')
        return window, area, region

    def override(self):
        window, area, region = self.viewport()
        return bpy.context.temp_override(window=window, area=area, region=region)

    def build_scene(self):
        scene = sdtest.empty_scene()
        sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
        self.ball = sdtest.ico_sphere(scene, subdivisions=3, location=(0.0, 0.0, 0.75), radius=0.75)
        self.ground = sdtest.grid(scene, cuts=30, size=4.0)
        white = sdtest.diffuse_material("White")     # the viewport shows B itself
        for obj in (self.ball, self.ground):
            obj.data.materials.append(white)
        sdtest.camera(scene, location=(0.0, -5.0, 2.5), target=(0.0, 0.0, 0.5))
        # Refined: its passes share the progress bar with the bake and cancel like it
        sdtest.bake_settings(scene, 'msd_visibility', 'PHONG', 4, 2, rays=256, phong_exponent=4.0,
                             select=[self.ball, self.ground], refine=True)
        return scene

    def read_viewport(self):
        """A POST_PIXEL handler copies the viewport's colour buffer (scene-linear before the
        view transform) once."""
        import gpu

        def grab():
            if self.samples is None:
                region = bpy.context.region
                framebuffer = gpu.state.active_framebuffer_get()
                buffer = framebuffer.read_color(0, 0, region.width, region.height, 4, 0, 'FLOAT')
                buffer.dimensions = region.width * region.height * 4
                self.samples = np.array(buffer, dtype=np.float32).reshape(region.height, region.width, 4)
                self.view = self.package.scene.view.View.from_region(bpy.context.region_data)
        return bpy.types.SpaceView3D.draw_handler_add(grab, (), 'WINDOW', 'POST_PIXEL')

    # -- the test, one step per timer tick
    def run(self):
        yield from self.shading()
        yield from self.sidebar()

    def shading(self):
        checks = self.checks
        package = self.package
        scene = self.build_scene()

        # Modal bake in a worker thread.
        with self.override():
            result = bpy.ops.sd_lighting.bake('INVOKE_DEFAULT')
        checks.check(result == {'RUNNING_MODAL'}, "bake starts as a modal operator", str(result))
        ticks_at_start, fractions = self.ticks, []
        while package.ui.operators.active_job is not None:
            fractions.append(package.ui.operators.active_job.fraction)
            yield
        checks.check(self.ticks - ticks_at_start >= 2, "the UI kept running during the bake",
                     "%d timer ticks" % (self.ticks - ticks_at_start))
        checks.check(fractions == sorted(fractions), "progress only grows",
                     "%s" % [round(f, 2) for f in fractions[:8]])
        checks.check(package.store.baked.baked_mesh(self.ball) is not None and
                     package.store.baked.baked_mesh(self.ground) is not None, "modal bake stored results")

        # Esc/cancel during a bake: nothing changes.
        bake_id = self.ball["sd_bake"]["bake_id"]
        meshes = sorted(m.name for m in bpy.data.meshes)
        scene.sd_lighting.rays = 8192
        with self.override():
            bpy.ops.sd_lighting.bake('INVOKE_DEFAULT')
        yield
        checks.check(package.ui.operators.active_job is not None, "second bake running")
        window = self.viewport()[0]
        if getattr(bpy.app, "use_event_simulate", False):
            # Blender started with --enable-event-simulate: press Esc for real.
            window.event_simulate(type='ESC', value='PRESS')
            window.event_simulate(type='ESC', value='RELEASE')
            how = "Esc"
        else:
            with self.override():
                bpy.ops.sd_lighting.cancel_bake()
            how = "the Cancel button"
        while package.ui.operators.active_job is not None:
            yield
        checks.check(self.ball["sd_bake"]["bake_id"] == bake_id and
                     sorted(m.name for m in bpy.data.meshes) == meshes,
                     "%s cancels a modal bake and nothing changes" % how, ", ".join(meshes))

        # The panel draws without errors.
        try:
            with self.override():
                sdtest.panel_texts()
            ok, detail = True, ""
        except Exception as exc:
            ok, detail = False, "%s: %s" % (type(exc).__name__, exc)
        checks.check(ok, "panel draws", detail)

        # Live shading in the viewport, seen through the scene camera.
        window, area, region = self.viewport()
        space = area.spaces.active
        space.shading.type = 'SOLID'
        space.region_3d.view_perspective = 'CAMERA'
        space.overlay.show_overlays = False
        scene.camera.data.show_passepartout = False
        handler = self.read_viewport()
        area.tag_redraw()
        for _ in range(3):
            yield
        bpy.types.SpaceView3D.draw_handler_remove(handler, 'WINDOW')
        checks.check(self.samples is not None, "viewport redrawn")
        checks.check(package.live.drawing.last_error == "", "draw handler ran without error",
                     package.live.drawing.last_error)
        if self.samples is None:
            return
        package.live.preview.write_png(os.path.join(self.args.out, "viewport.png"),
                                  np.round(255 * np.clip(self.samples[::-1], 0, 1)).astype(np.uint8))
        drawing = package.live.drawing
        shaded = []     # (x, y) of the vertices compared
        for obj in (self.ball, self.ground):
            cpu = drawing.cpu_reference(scene, obj, self.view)
            mesh = package.store.baked.baked_mesh(obj)
            matrix = np.array(obj.matrix_world)
            world = package.store.attributes.read_positions(mesh) @ matrix[:3, :3].T + matrix[:3, 3]
            clip = np.c_[world, np.ones(len(world))] @ self.view.view_projection.T
            ndc = clip[:, :3] / clip[:, 3:4]
            h, w = self.samples.shape[:2]
            x, y = (ndc[:, 0] + 1) * 0.5 * w, (ndc[:, 1] + 1) * 0.5 * h   # rows bottom-first here
            to_eye = self.view.camera[:3] - world
            normals = package.store.attributes.read_normals(mesh) @ matrix[:3, :3].T
            facing = (to_eye * normals).sum(axis=1) > 0.3 * np.linalg.norm(to_eye, axis=1)
            inside = facing & (x > 2) & (x < w - 2) & (y > 2) & (y < h - 2)
            inside &= ~boundary_vertices(package.store.attributes.read_triangles(mesh), len(world))
            inside &= unoccluded(scene, bpy.context.evaluated_depsgraph_get(), self.view.camera[:3], world)
            # The viewport's buffer holds the display values: sRGB(B) in 8 bits (Standard view
            # transform), read back as they are stored.
            inside &= (cpu.min(axis=1) > 0.02) & (cpu.max(axis=1) < 0.98)
            px = sdtest.bilinear(self.samples, x[inside], y[inside])
            shaded.append((x[inside], y[inside]))
            expected = package.live.preview.srgb_encode(cpu[inside])
            error = 255.0 * np.abs(px - expected).max(axis=1)
            checks.check(inside.sum() > 20 and np.median(error) < 1.5 and np.mean(error < 4.0) > 0.9,
                         "viewport shows sRGB(B of the CPU evaluator) on the %s" % obj.name,
                         "median %.2f / 255 over %d vertices, %.0f %% within 4 / 255" % (
                             np.median(error), inside.sum(), 100 * np.mean(error < 4.0)))

        # The World Background option: the empty pixels (those of the Solid mode's background
        # colour in the top row) show sRGB(L(g d)) of each pixel's ray d; the objects stay.
        before = self.samples
        empty = np.all(np.abs(before - np.median(before[-1], axis=0)) < 1e-6, axis=2)
        scene.sd_lighting.world_background = True
        self.samples = None
        handler = self.read_viewport()
        area.tag_redraw()
        for _ in range(3):
            yield
        bpy.types.SpaceView3D.draw_handler_remove(handler, 'WINDOW')
        scene.sd_lighting.world_background = False
        if not checks.check(self.samples is not None and package.live.drawing.last_error == "",
                            "viewport redrawn with the world background", package.live.drawing.last_error):
            return
        h, w = empty.shape
        rows, columns = np.nonzero(empty)
        ndc = np.stack([2.0 * (columns + 0.5) / w - 1.0, 2.0 * (rows + 0.5) / h - 1.0], axis=1)
        inverse = np.linalg.inv(self.view.view_projection)
        near, far = (np.c_[ndc, np.full(len(ndc), z), np.ones(len(ndc))] @ inverse.T for z in (0.0, 0.5))
        rays = far[:, :3] / far[:, 3:] - near[:, :3] / near[:, 3:]
        rays /= np.linalg.norm(rays, axis=1, keepdims=True)
        e = rays @ package.scene.environment.rotation_matrix(scene).T
        u = 0.5 - np.arctan2(e[:, 1], e[:, 0]) / (2.0 * np.pi)
        v = 1.0 - np.arccos(np.clip(e[:, 2], -1.0, 1.0)) / np.pi
        # The map, bilinear as Blender's Environment Texture (one texel of wrap and pole padding)
        texels = package.scene.environment.background_texels(package.scene.environment.source(scene))
        texels = np.concatenate([texels[:, -1:], texels, texels[:, :1]], axis=1)
        texels = np.concatenate([texels[:1], texels, texels[-1:]], axis=0)
        height, width = texels.shape[0] - 2, texels.shape[1] - 2
        radiance = sdtest.bilinear(texels, u * width + 1.0, v * height + 1.0)
        error = 255.0 * np.abs(self.samples[rows, columns, :3] - package.live.preview.srgb_encode(radiance)).max(axis=1)
        checks.check(len(error) > 1000 and np.median(error) < 1.5 and np.mean(error < 4.0) > 0.9,
                     "the world background fills the empty pixels with sRGB(L(g d))",
                     "median %.2f / 255 over %d pixels, %.0f %% within 4 / 255" % (
                         np.median(error), len(error), 100 * np.mean(error < 4.0)))
        package.live.preview.write_png(os.path.join(self.args.out, "viewport_background.png"),
                                  np.round(255 * np.clip(self.samples[::-1], 0, 1)).astype(np.uint8))
        x, y = (np.concatenate(c) for c in zip(*shaded))
        moved = 255.0 * np.abs(sdtest.bilinear(self.samples, x, y) - sdtest.bilinear(before, x, y)).max(axis=1)
        checks.check(np.median(moved) < 0.5 and np.mean(moved < 2.0) > 0.95,
                     "the world background leaves the shaded objects as they were",
                     "median %.2f / 255 over %d vertices" % (np.median(moved), len(moved)))

    # -- the sidebar
    def sidebar(self):
        """The sidebar at its default width on the SD Lighting tab, the baked ball active and
        selected, the settings the bake's but for the method (Automatic, the default, predicted in
        the background first): its texts fit; with --screenshots, its pages as the panels first
        open (panel.png) and with every sub-panel open (panel_open.png)."""
        checks, package = self.checks, self.package
        if not getattr(bpy.app, "use_event_simulate", False):
            print("test_viewport: no sidebar screenshots (selecting its tab needs --enable-event-simulate)")
            return
        scene = bpy.context.scene
        scene.sd_lighting.rays = 256
        scene.sd_lighting.method = 'automatic'
        sdtest.select_only([self.ball])
        bpy.context.view_layer.objects.active = self.ball
        window, area, _ = self.viewport()
        area.spaces.active.show_region_ui = True
        shown = yield from self.show_tab(window, area)
        ui = next(r for r in area.regions if r.type == 'UI')
        scale = bpy.context.preferences.system.ui_scale
        checks.check(shown, "the sidebar shows the SD Lighting tab", "%d pixels wide, %.0f at UI scale 1"
                     % (ui.width, ui.width / scale))
        if not shown:
            with bpy.context.temp_override(window=window, area=area):   # what it shows instead
                bpy.ops.screen.screenshot_area(filepath=os.path.join(self.args.out, "no_panel.png"))
            return
        # Every text the panels draw fits a line of the sidebar (wrapped, or short).
        with bpy.context.temp_override(window=window, area=area, region=ui):
            width = package.ui.panels._chars(bpy.context)
            too_long = [text for text in sdtest.panel_texts() if width is not None and len(text) > width]
        checks.check(width is not None and not too_long, "every text of the panels fits a line of the "
                     "sidebar (%s characters)" % width, "; ".join(too_long[:3]))
        if not self.screenshots:
            return
        for _ in range(300):         # the automatic mode's prediction, measured in the background
            if package.ui.prediction.predicted_errors(bpy.context):
                break
            area.tag_redraw()
            yield
        pages = yield from self.sidebar_pages(window, area, "panel")

        # Every sub-panel open: registered without DEFAULT_CLOSED, in another workspace, whose 3D
        # view has not drawn them yet (a region keeps the panels' open state it has).
        workspace = bpy.data.workspaces.get("Modeling")
        if workspace is not None:
            closed = self.register_panels(open_all=True)
            workspace.object_mode = 'OBJECT'
            window.workspace = workspace
            yield
            yield
            area = max((a for a in window.screen.areas if a.type == 'VIEW_3D'),
                       key=lambda a: a.width * a.height)
            area.spaces.active.show_region_ui = True
            if (yield from self.show_tab(window, area)):
                pages += yield from self.sidebar_pages(window, area, "panel_open")
            self.register_panels(open_all=False, closed=closed)
        checks.check(bool(pages) and all(os.path.getsize(path) > 1000 for path in pages),
                     "the sidebar's screenshots are saved", " ".join(pages))
        for path in pages:
            print("test_viewport: sidebar screenshot %s" % path)

    def show_tab(self, window, area):
        """Selects the SD Lighting tab of the area's sidebar (Ctrl+Wheel over its tabs, one tab a
        step; Blender 3.4 has no API for it) until the panel draws; whether it did."""
        ui = next(r for r in area.regions if r.type == 'UI')
        panel = self.package.ui.panels.SD_PT_lighting
        draw, drawn = panel.draw, []

        def watched(panel_self, context):
            drawn.append(True)
            draw(panel_self, context)
        panel.draw = watched
        try:
            for _ in range(10):
                drawn.clear()
                area.tag_redraw()
                for _ in range(3):
                    yield
                if drawn:
                    return True
                x, y = ui.x + ui.width - 10, ui.y + ui.height - 20     # over the tabs
                window.event_simulate(type='MOUSEMOVE', value='NOTHING', x=x, y=y)
                window.event_simulate(type='WHEELDOWNMOUSE', value='PRESS', x=x, y=y, ctrl=True)
            return False
        finally:
            panel.draw = draw

    def sidebar_shot(self, window, area):
        """The area's sidebar as it is on screen (RGBA8, rows top-first)."""
        ui = next(r for r in area.regions if r.type == 'UI')
        path = os.path.join(self.args.out, "area.png")
        with bpy.context.temp_override(window=window, area=area):
            bpy.ops.screen.screenshot_area(filepath=path)
        image = bpy.data.images.load(path)
        try:
            width, height = image.size
            pixels = np.empty(height * width * 4, dtype=np.float32)
            image.pixels.foreach_get(pixels)   # pixels[:] is a list of millions of floats: seconds
            pixels = pixels.reshape(height, width, 4)
        finally:
            bpy.data.images.remove(image)
            os.remove(path)
        x, y = ui.x - area.x, ui.y - area.y
        return np.round(255 * pixels[y:y + ui.height, x:x + ui.width][::-1]).astype(np.uint8)

    def sidebar_pages(self, window, area, stem, most=6):
        """Screenshots of the sidebar, a page at a time down to its end: STEM.png, STEM_2.png...
        under --out; their paths."""
        ui = next(r for r in area.regions if r.type == 'UI')
        for _ in range(3):
            yield
        paths, previous = [], None
        for page in range(most):
            shot = self.sidebar_shot(window, area)
            if previous is not None and np.array_equal(shot, previous):
                break
            paths.append(os.path.join(self.args.out, "%s%s.png" % (stem, "_%d" % (page + 1) if page else "")))
            self.package.live.preview.write_png(paths[-1], shot)
            previous = shot
            with bpy.context.temp_override(window=window, area=area, region=ui):
                bpy.ops.view2d.scroll_down(page=True)
            for _ in range(3):
                yield
        return paths

    def register_panels(self, open_all, closed=()):
        """Registers the panels again, every one open (open_all; returns those that start
        closed), or as they were."""
        panels = self.package.ui.panels
        panels.unregister()
        if open_all:
            closed = [cls for cls in panels.CLASSES if 'DEFAULT_CLOSED' in getattr(cls, "bl_options", ())]
        for cls in closed:
            cls.bl_options = set() if open_all else {'DEFAULT_CLOSED'}
        panels.register()
        return closed

    def tick(self):
        self.ticks += 1
        try:
            next(self.steps)
        except StopIteration:
            sdtest.finish(self.checks.summary())
        except Exception:
            import traceback
            traceback.print_exc()
            sdtest.finish(1)
        if self.start is not None and self.ticks * 0.1 > TIMEOUT:
            print("test_viewport: timed out")
            sdtest.finish(1)
        return 0.1


def main():
    # A fresh user folder shows the first-run splash after this script, over the viewport and the
    # sidebar (and taking the events the test simulates): not in this run.
    bpy.context.preferences.view.show_splash = False
    test = Test()
    test.start = 0.0
    bpy.app.timers.register(test.tick, first_interval=0.5)


try:
    main()
except Exception:
    import traceback
    traceback.print_exc()
    sdtest.finish(1)
