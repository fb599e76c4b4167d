"""The add-on installs from the zip, registers, and unregisters leaving nothing behind.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_register.py -- --zip Z
"""

import importlib.machinery
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402


def main():
    checks = sdtest.Checks("test_register")
    args = sdtest.arguments()
    before = sdtest.registration_state()
    package = sdtest.install_addon(args.zip)
    checks.check(os.path.dirname(package.__file__).endswith("sd_lighting") and
                 "scripts" in package.__file__, "imported from the installed zip", package.__file__)
    checks.check(package.bl_info["blender"] <= (3, 4, 0), "bl_info targets Blender 3.4")
    on = sdtest.registration_state()
    for key in ("scene_property", "panel", "bake_operator", "preview_operator"):
        checks.check(on[key], "registered: " + key)
    added = {name: on["handlers"][name] - before["handlers"][name] for name in on["handlers"]}
    checks.check(added == {"load_post": 2, "save_pre": 1, "depsgraph_update_post": 1, "frame_change_post": 1,
                           "undo_post": 1, "redo_post": 1},
                 "the handlers of a file's load and save and of stale bakes added", str(added))
    checks.check(package.live.drawing._handler is not None, "draw handler added")
    checks.check(package.native.available(), "sdnative loads from the zip",
                 package.native.error_message())
    sd = package.native.get()
    checks.check(os.path.dirname(sd.__file__) == os.path.join(os.path.dirname(package.__file__),
                                                               package.native.WHEEL_PACKAGE),
                 "sdnative is the zip's copy (its wheel's files, inside the package)", sd.__file__)
    native = package.native
    portable = os.path.join(os.path.dirname(sd.__file__), native.PORTABLE + importlib.machinery.EXTENSION_SUFFIXES[0])
    build = native.builds(native.supports_x86_64_v3(portable), os.environ.get("SDNATIVE_BUILD"))[0]
    checks.check(os.path.basename(sd.__file__).startswith(build + "."),
                 "sdnative is the build for this CPU (%s)" % build, sd.__file__)
    checks.check(os.path.isdir(package.live.gpu_shading.shader_directory()) and
                 package.live.gpu_shading.shader_directory().startswith(os.path.dirname(package.__file__)),
                 "shaders are the zip's copy", package.live.gpu_shading.shader_directory())
    settings = bpy.context.scene.sd_lighting
    checks.check(settings.method == "automatic" and settings.visibility_order == 2,
                 "default settings: the automatic mode, s' = 2 for a chosen method")
    drawing = package.live.drawing
    live = package.live.live_rebake
    checks.check(not settings.live_rebake, "Live Re-bake is off by default")
    settings.live_rebake = True
    handlers = sdtest.registration_state()["handlers"]
    checks.check(all(handlers[name] == on["handlers"][name] + (name in sdtest.LIVE_REBAKE_HANDLERS)
                     for name in handlers), "Live Re-bake on: its handlers are added", str(handlers))
    live._mark(["Cube"])           # a change waiting for its re-bake: the timer runs
    checks.check(bpy.app.timers.is_registered(live._tick), "a change starts the re-bake timer")
    settings.live_rebake = False
    checks.check(sdtest.registration_state() == on and not bpy.app.timers.is_registered(live._tick)
                 and not live.pending(), "Live Re-bake off: handlers, timer and changes are gone")
    settings.live_rebake = True
    live._mark(["Cube"])

    import addon_utils
    for cycle in range(2):
        addon_utils.disable("sd_lighting")
        off = sdtest.registration_state()
        checks.check(off == before, "unregister leaves nothing behind (cycle %d)" % cycle,
                     "%s vs %s" % (off, before))
        checks.check(drawing._handler is None, "draw handler removed (cycle %d)" % cycle)
        checks.check(not bpy.app.timers.is_registered(live._tick) and not live.pending(),
                     "live re-bake timer and changes removed (cycle %d)" % cycle)
        addon_utils.enable("sd_lighting")
        # The scene still has Live Re-bake on: its handlers come back at the first timer (bpy.data
        # is not readable while an add-on registers).
        checks.check(bpy.app.timers.is_registered(live.sync) and
                     sdtest.registration_state() == on, "registered; Live Re-bake waits for a timer")
        live.sync()
        again = sdtest.registration_state()
        checks.check(again == dict(on, handlers=handlers), "registers again (cycle %d)" % cycle,
                     str(again))
    return checks.summary()


sdtest.run(main)
