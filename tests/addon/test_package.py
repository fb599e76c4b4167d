"""The package imports without Blender; only register() needs bpy."""

import importlib
import pkgutil
import sys

import pytest

import sd_lighting
import sd_lighting.utils


def test_no_bpy_here():
    with pytest.raises(ImportError):
        importlib.import_module("bpy")


def test_bl_info_and_registration_entry_points():
    assert sd_lighting.bl_info["name"] == "SD Lighting"
    assert sd_lighting.bl_info["blender"] == (3, 4, 0)
    assert callable(sd_lighting.register) and callable(sd_lighting.unregister)


def test_every_utils_module_imports_without_bpy():
    names = [m.name for m in pkgutil.iter_modules(sd_lighting.utils.__path__)]
    assert {"bake_data", "methods", "lobes", "transforms", "limits", "shader_variant"} <= set(names)
    for name in names:
        importlib.import_module("sd_lighting.utils." + name)
    assert "bpy" not in sys.modules


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
