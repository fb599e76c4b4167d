"""The native module of the sd-lighting Blender add-on, as its wheel installs it (pyproject.toml):
sdnative built for this CPython, and beside it sdnative_x86_64_v3, the same module for x86-64-v3
CPUs. Both define the module `sdnative`: the add-on's native.py picks one by the CPU's level and
loads it by its file, so nothing here imports either."""
