"""The package imports without Blender; only register() needs bpy."""

import importlib
import sys

import pytest

import sd_lighting


def test_no_bpy_here():
    with pytest.raises(ImportError):
        importlib.import_module("bpy")


def test_bl_info_and_registration_entry_points():
    assert sd_lighting.bl_info["name"] == "SD Lighting"
    assert sd_lighting.bl_info["blender"] == (3, 4, 0)
    assert callable(sd_lighting.register) and callable(sd_lighting.unregister)


# The pure logic beside the bpy modules of each sub-package, tested here without Blender.
PURE = {"background", "errors", "methods", "native",
        "scene.lobes", "scene.transforms", "scene.ringing", "scene.view",
        "plan.accuracy", "plan.automatic", "plan.bake_time", "plan.cost",
        "bake.corners", "bake.least_squares", "bake.lightmap", "bake.refine",
        "store.bake_data", "store.record",
        "live.lobe_designs", "live.rebake_schedule", "live.shader_variant",
        "ui.limits"}


def test_the_pure_modules_import_without_bpy():
    assert PURE <= set(sd_lighting._SUBMODULES)
    for name in sorted(PURE):
        importlib.import_module("sd_lighting." + name)
    assert "bpy" not in sys.modules


def test_sub_packages_import_nothing():
    """A sub-package's __init__ imports nothing, so importing one of its pure modules needs no bpy."""
    import ast
    import os
    for name in ("scene", "plan", "bake", "store", "live", "ui"):
        path = os.path.join(os.path.dirname(sd_lighting.__file__), name, "__init__.py")
        tree = ast.parse(open(path, encoding="utf-8").read())
        assert not [node for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))], name


def test_reload_list_names_every_submodule():
    """__init__ reloads its submodules on F3 > Reload Scripts: the list must be complete."""
    import os
    root = os.path.dirname(sd_lighting.__file__)
    found = set()
    for directory, _, files in os.walk(root):
        for name in files:
            if name.endswith(".py") and name != "__init__.py":
                relative = os.path.relpath(os.path.join(directory, name), root)
                found.add(relative[:-3].replace(os.sep, "."))
    assert found == set(sd_lighting._SUBMODULES)


def test_registration_needs_bpy():
    with pytest.raises(ImportError):
        sd_lighting.register()


def _package_imports(path, module):
    """The package's modules that `module` (dotted, e.g. utils.methods) imports."""
    import ast
    tree = ast.parse(open(path, encoding="utf-8").read())
    base = module.split(".")[:-1]
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level > 0:
            parent = base[:len(base) - (node.level - 1)] if node.level > 1 else base
            target = parent + (node.module.split(".") if node.module else [])
            for alias in node.names:
                candidate = ".".join(target + [alias.name])
                out.add(candidate if candidate in sd_lighting._SUBMODULES else ".".join(target))
    return {name for name in out if name in sd_lighting._SUBMODULES}


def test_reload_order_puts_dependencies_first():
    import os
    root = os.path.dirname(sd_lighting.__file__)
    order = {name: index for index, name in enumerate(sd_lighting._SUBMODULES)}
    for name in sd_lighting._SUBMODULES:
        path = os.path.join(root, *name.split(".")) + ".py"
        for dependency in _package_imports(path, name):
            assert order[dependency] < order[name], (name, dependency)
