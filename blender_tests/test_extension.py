"""The extension zip is a valid Blender 4.2+ extension: Blender's own validator accepts its manifest,
it installs through the extension operator (Get Extensions > Install from Disk) into the user
repository, registers as bl_ext.user_default.sd_lighting with the shaders from the extension's
folder and the native module from the wheel of its Python that Blender installed, disables and enables twice leaving nothing behind, bakes and renders a
preview from there, and uninstalls.
Run (Blender 4.2+, or Blender 4.2+ as a Python module):
    blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_extension.py -- --zip Z --out DIR
"""

import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402


def validate(zip_path):
    """Blender's manifest validator on the zip: `blender --command extension validate ZIP` where
    this is a Blender binary, else the same command-line tool (bl_pkg's blender_ext.py) run by
    this Python (Blender as a module has no --command). Returns (exit code, output)."""
    binary = bpy.app.binary_path
    if binary and os.path.basename(binary).startswith("blender"):
        command = [binary, "--factory-startup", "--command", "extension", "validate", zip_path]
    else:
        script = os.path.join(bpy.utils.system_resource('SCRIPTS'), "addons_core", "bl_pkg", "cli",
                              "blender_ext.py")
        command = [sys.executable, script, "validate", zip_path]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300)
    return done.returncode, (done.stdout + done.stderr).strip()


def bl_info_of(path):
    import ast
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read())
    node = next(n for n in tree.body if isinstance(n, ast.Assign) and
                getattr(n.targets[0], "id", None) == "bl_info")
    return ast.literal_eval(node.value)


def main():
    import addon_utils
    import tomllib
    checks = sdtest.Checks("test_extension")
    args = sdtest.arguments()

    code, output = validate(args.zip)
    checks.check(code == 0, "Blender's extension validator accepts the zip", output.splitlines()[-1]
                 if output else "exit %d" % code)

    before = sdtest.registration_state()
    package = sdtest.install_extension(args.zip)
    module = sdtest.addon_module
    root = os.path.dirname(package.__file__)
    extensions = os.environ.get("BLENDER_USER_EXTENSIONS") or bpy.utils.user_resource('EXTENSIONS')
    checks.check(package.__name__ == "bl_ext.user_default.sd_lighting" and
                 root.startswith(os.path.join(extensions, "user_default")),
                 "installed as the extension bl_ext.user_default.sd_lighting", root)
    checks.check(module in bpy.context.preferences.addons, "enabled on install")
    with open(os.path.join(root, "blender_manifest.toml"), "rb") as f:
        manifest = tomllib.load(f)
    # Blender drops bl_info from an extension's module: read it from the installed source.
    bl_info = bl_info_of(os.path.join(root, "__init__.py"))
    checks.check(manifest["id"] == "sd_lighting" and
                 tuple(int(p) for p in manifest["version"].split(".")) == bl_info["version"],
                 "manifest id and version agree with bl_info", "%s %s" % (manifest["id"], manifest["version"]))
    pythons = sorted(set(re.findall(r"-(cp3\d+)-", " ".join(manifest.get("wheels", [])))))
    checks.check(manifest.get("blender_version_max") == (None if "cp313" in pythons else "5.1.0"),
                 "blender_version_max matches the wheels' Pythons",
                 "%s: %s" % (", ".join(pythons), manifest.get("blender_version_max")))
    on = sdtest.registration_state()
    for key in ("scene_property", "panel", "bake_operator", "preview_operator"):
        checks.check(on[key], "registered: " + key)
    # The native module comes as a wheel per CPython (issue 31): Blender installs the one of its
    # Python into the extensions' own site-packages.
    python = "-cp%d%d-" % sys.version_info[:2]
    checks.check(any(python in w for w in manifest.get("wheels", [])) and
                 all(os.path.isfile(os.path.join(root, w)) for w in manifest.get("wheels", [])),
                 "the manifest lists the wheels it carries, one of them this Python's",
                 ", ".join(manifest.get("wheels", [])))
    loaded = package.native.get().__file__ if package.native.available() else package.native.error_message()
    site = os.path.join(extensions, ".local")
    checks.check(os.path.realpath(loaded).startswith(os.path.realpath(site) + os.sep) and
                 os.path.basename(os.path.dirname(loaded)) == package.native.WHEEL_PACKAGE,
                 "sdnative loads from the wheel Blender installed", loaded)
    checks.check(package.live.gpu_shading.shader_directory().startswith(root),
                 "shaders are the extension's copy", package.live.gpu_shading.shader_directory())

    for cycle in range(2):
        addon_utils.disable(module)
        off = sdtest.registration_state()
        checks.check(off == before, "disable leaves nothing behind (cycle %d)" % cycle,
                     "%s vs %s" % (off, before))
        addon_utils.enable(module)
        checks.check(sdtest.registration_state() == on, "enables again (cycle %d)" % cycle)

    # Bake and preview from the extension.
    scene = sdtest.empty_scene()
    sdtest.hdri_world(scene, sdtest.hdri("forest.exr"))
    ball = sdtest.ico_sphere(scene, subdivisions=2, location=(0.0, 0.0, 0.8), radius=0.8)
    ground = sdtest.grid(scene, cuts=8, size=4.0)
    sdtest.camera(scene)
    sdtest.bake_settings(scene, 'msd_visibility', 'LAMBERT', 3, 2, rays=64, select=[ball, ground])
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'}, "bake")
    baked = package.store.baked.baked_mesh(ball)
    checks.check(baked is not None and "sd_design_count" in baked.attributes and
                 "sd_normal" in baked.attributes, "baked mesh with its attributes")
    path = os.path.join(args.out, "extension_preview.png")
    checks.check(bpy.ops.sd_lighting.render_preview(filepath=path, width=160, height=120) == {'FINISHED'},
                 "render_preview")
    image = package.live.preview.read_png(path)
    covered = image[..., 3] > 127
    checks.check(image.shape == (120, 160, 4) and 0.1 < covered.mean() < 0.99 and
                 image[covered][:, :3].max() > 20, "the preview shows the lit scene",
                 "%.0f %% covered" % (100 * covered.mean()))

    sdtest.select_only([ball])
    checks.check(bpy.ops.sd_lighting.clear_bake() == {'FINISHED'}, "clear bake")
    repo_index = next(i for i, repo in enumerate(bpy.context.preferences.extensions.repos)
                      if repo.module == sdtest.EXTENSION_REPOSITORY)
    result = bpy.ops.extensions.package_uninstall(repo_index=repo_index, pkg_id="sd_lighting")
    checks.check(result == {'FINISHED'} and not os.path.exists(root) and sdtest.registration_state() == before and
                 module not in bpy.context.preferences.addons and not os.path.exists(os.path.dirname(loaded)),
                 "uninstall removes the extension and its wheel's files",
                 "%s, %s" % (result, sdtest.registration_state()))
    sdtest.addon_module = None
    return checks.summary()


sdtest.run(main)
