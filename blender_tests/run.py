#!/usr/bin/env python3
"""Runs the Blender tests of the add-on: each test script in its own Blender process, headless.

    python3 blender_tests/run.py --zip build/sd_lighting.zip --out build/blender_tests [TEST ...]
    python3 blender_tests/run.py --bpy 4.5.15 --zip build/sd_lighting.zip --out DIR [TEST ...]

TEST names a test (test_bake, ...; default: all of TESTS, in order). Two kinds of Blender run them:

- a Blender binary (`--blender`, default Debian's /usr/bin/blender): `blender -b --factory-startup
  --python-exit-code 1 --python SCRIPT -- ARGS`; tests that need a GPU context or a window run
  under `xvfb-run -a blender --factory-startup ...` instead;
- Blender as a Python module (`--bpy VERSION`, one of blender_tests/bpy_versions.txt, installed by
  blender_tests/bpy_modules.py; a version whose CPython is not on the machine is skipped):
  `VENV/bin/python SCRIPT -- ARGS`. The module behaves like
  `blender -b`: GPU tests get their context from a Workbench render (gpu_context.ensure(), EGL with
  Mesa's llvmpipe); tests that need a window and Blender's event loop (test_viewport: modal
  operators, timers, a simulated Esc) cannot run there and are reported as skipped.

A test may also need a minimum Blender version (test_extension: extensions exist since 4.2);
below it, it is skipped. Every run gets its own BLENDER_USER_SCRIPTS/BLENDER_USER_CONFIG (and
extension repository, and the add-on's cache) under --out, so installing the zip never touches
~/.config/blender. test_shader_variants also gets fresh shader caches, so every variant is really
compiled; the other tests share a shader cache per Blender (Blender's own - the SPIR-V of its
Vulkan backend - and Mesa's), kept between runs like the bpy venvs, in
${XDG_CACHE_HOME:-~/.cache}/sd-lighting/shader-cache/: a program that an earlier test or run
compiled from the same source with the same compiler is loaded, not compiled again (a program
that fails to compile is never cached). SD_FRESH_SHADER_CACHES=1 gives every test fresh ones. Prints
one line per test and a summary; exits non-zero if any test fails, and with SKIPPED (77) when
every selected test was skipped (CTest's SKIP_RETURN_CODE).

`--quick` passes --quick to each script: the quick tier's part of the test where it has one
(test_shader_variants: one variant per #define; test_gpu_matches_cpu, test_material_colour,
test_world_render: fewer cases, each script's doc says which). `--no-numeric` passes --no-numeric: the scripts
leave out their version-independent numeric checks (test_scale, test_ringing, test_automatic),
which the CTest suite runs on Debian's Blender only.
`--benchmark` runs blender_tests/benchmark_viewport.py instead (prints the frame-time table).
`--main-job DIR` runs blender_tests/run_default_scene.py with --out DIR instead.
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bpy_modules  # noqa: E402

SKIPPED = 77

# What a test needs from the Blender that runs it:
BACKGROUND = "background"  # nothing: blender -b, or the bpy module
GPU = "gpu"                # a GPU context: xvfb-run blender, or the module's Workbench-render context
WINDOW = "window"          # a window and the event loop: xvfb-run blender only

# (script, needs, time limit in seconds, extra Blender options, script arguments, first version)
TESTS = [
    ("test_register", BACKGROUND, 120, [], [], (3, 4, 0)),
    ("test_extension", BACKGROUND, 300, [], [], (4, 2, 0)),
    ("test_bake", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_default_scene", BACKGROUND, 600, [], [], (3, 4, 0)),
    ("test_portable", BACKGROUND, 300, [], [], (4, 2, 0)),
    ("test_shader_variants", GPU, 600, [], [], (3, 4, 0)),
    ("test_gpu_matches_cpu", GPU, 600, [], [], (3, 4, 0)),
    ("test_gpu_hard_cases", GPU, 300, [], [], (3, 4, 0)),
    ("test_background_builds", GPU, 600, [], [], (3, 4, 0)),
    ("test_preview", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_source_shadows", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_shader_rebind", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_world_orientation", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_material_colour", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_scale", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_ringing", GPU, 300, [], [], (3, 4, 0)),
    ("test_automatic", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_texture_space", BACKGROUND, 300, [], [], (3, 4, 0)),
    # GPU: the binary runs under Xvfb, with a window, so it has an undo stack to test
    ("test_robustness", GPU, 300, [], [], (3, 4, 0)),
    # GPU: the shading is checked per vertex; under Xvfb the binary also has an undo stack
    ("test_live_rebake", GPU, 300, [], [], (3, 4, 0)),
    ("test_stale_bake", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_world_render", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_instances", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_two_sided", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_large_bakes", BACKGROUND, 300, [], [], (3, 4, 0)),
    ("test_viewport", WINDOW, 600, ["--enable-event-simulate"], [], (3, 4, 0)),
    # the accuracy-cost report's quick variant and its invariants (issue 11)
    ("accuracy_report", BACKGROUND, 600, [], ["--quick"], (3, 4, 0)),
    # parity with Cycles on Debian's real assets (issue 8, item 7)
    ("test_cycles_parity", BACKGROUND, 1500, [], [], (3, 4, 0)),
]


class BlenderBinary:
    """A Blender executable."""

    def __init__(self, path):
        self.path = self.where = path
        self.version, self.label = (0, 0, 0), "blender"
        try:
            text = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=120,
                                  env=blender_environment(None)).stdout
            match = re.search(r"^Blender (\d+)\.(\d+)\.(\d+)", text, re.M)
            if match:
                self.version = tuple(int(g) for g in match.groups())
                self.label = "Blender %d.%d.%d" % self.version
        except (OSError, subprocess.SubprocessError):
            pass

    def skip_reason(self, needs):
        return None

    def command(self, script, needs, options, arguments):
        command = [self.path]
        if needs in (GPU, WINDOW):
            command = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24"] + command
        else:
            command.append("-b")
        return command + ["--factory-startup"] + list(options) + [
            "--python-exit-code", "1", "--python", os.path.join(HERE, script + ".py"), "--"] + arguments


class BlenderModule:
    """Blender as a Python module (the bpy wheel) in its virtual environment."""

    def __init__(self, version):
        self.python = self.where = bpy_modules.interpreter(version)
        self.version = tuple(int(p) for p in version.split(".")[:3])
        python = bpy_modules.pins()[version]
        self.label = "bpy %s (module, CPython %s)" % (version, python)
        self.missing = None
        if not bpy_modules.installed(version):
            if bpy_modules.find_python(python) is None:
                self.missing = "bpy %s needs CPython %s, not found on this machine" % (version, python)
            else:
                raise SystemExit("run.py: bpy %s is not installed (%s); run: /usr/bin/python3 "
                                 "blender_tests/bpy_modules.py install %s" % (version, self.python, version))

    def skip_reason(self, needs):
        if self.missing:
            return self.missing
        if needs == WINDOW:
            return "needs a window and Blender's event loop; the bpy module has neither"
        return None

    def command(self, script, needs, options, arguments):
        return [self.python, os.path.join(HERE, script + ".py"), "--"] + arguments


def blender_environment(user):
    """The environment for Blender: its own user folders (`user`; None: leave them), and no trace
    of another Python (a pyenv interpreter running this script puts its bin/ first on PATH, and
    Blender - embedding the system's Python 3.11 - would then take that installation's prefix and
    miss Debian's numpy)."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("PYENV") and k not in ("PYTHONHOME", "PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep)
                                  if "/.pyenv/" not in p and "/virtualenvs/" not in p)
    if user is not None:
        env["BLENDER_USER_SCRIPTS"] = os.path.join(user, "scripts")
        env["BLENDER_USER_CONFIG"] = os.path.join(user, "config")
        env["BLENDER_USER_EXTENSIONS"] = os.path.join(user, "extensions")   # 4.2+
        env["BLENDER_USER_DATAFILES"] = os.path.join(user, "datafiles")
        # Blender's shader caches (OpenGL, Vulkan SPIR-V and pipelines) and Mesa's live under
        # $XDG_CACHE_HOME (and the add-on's, always fresh): run_one links the shader caches to
        # the shared ones (FRESH_SHADER_CACHES).
        env["XDG_CACHE_HOME"] = os.path.join(user, "cache")
        # ... but the venvs' cache stays the runner's (the tools venv: sdtest.perceptual_error)
        env["SD_BPY_CACHE"] = bpy_modules.cache_directory()
    return env


# The tests whose shader caches are fresh: they check that every program compiles.
FRESH_SHADER_CACHES = {"test_shader_variants"}
SHADER_CACHES = ("blender", "mesa_shader_cache", "mesa_shader_cache_db")   # under $XDG_CACHE_HOME


def share_shader_caches(blender, user):
    """Links the shader caches of the run's $XDG_CACHE_HOME (user/cache) to the shared ones of
    this Blender (see the module's doc)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    shared = os.path.join(base, "sd-lighting", "shader-cache", "%s-%d.%d.%d" % (
        "bpy" if isinstance(blender, BlenderModule) else "blender", *blender.version[:3]))
    os.makedirs(os.path.join(user, "cache"), exist_ok=True)
    for name in SHADER_CACHES:
        os.makedirs(os.path.join(shared, name), exist_ok=True)
        os.symlink(os.path.join(shared, name), os.path.join(user, "cache", name))


def run_one(blender, name, needs, limit, zip_path, out, script_out=None, options=(), arguments=()):
    """Runs one script; its log goes under `out`, the script writes its files to `script_out`
    (default `out`). Blender's user folders (the installed add-on, about 50 MB) are removed
    afterwards: kept, the full tier's 130 runs filled CI's disk."""
    user = os.path.join(out, "blender_user", name)
    shutil.rmtree(user, ignore_errors=True)
    os.makedirs(user, exist_ok=True)
    if name not in FRESH_SHADER_CACHES and os.environ.get("SD_FRESH_SHADER_CACHES") != "1":
        share_shader_caches(blender, user)
    env = blender_environment(user)
    command = blender.command(name, needs, options,
                              ["--zip", zip_path, "--out", script_out or out] + list(arguments))
    log_path = os.path.join(out, name + ".log")
    start = time.perf_counter()
    with open(log_path, "w") as log:
        log.write("# %s\n" % " ".join(command))
        log.flush()
        try:
            code = subprocess.run(command, env=env, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=limit).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
    seconds = time.perf_counter() - start
    shutil.rmtree(user, ignore_errors=True)   # unlinks the shared caches' links, not the caches
    with open(log_path, errors="replace") as log:
        text = log.read()
    return code, seconds, text, log_path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--zip", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--blender", default=shutil.which("blender") or "/usr/bin/blender",
                        help="a Blender executable (default: blender on PATH)")
    parser.add_argument("--bpy", metavar="VERSION", choices=bpy_modules.versions(),
                        help="run in Blender as a Python module, this pinned version, instead")
    parser.add_argument("--benchmark", action="store_true")
    parser.add_argument("--main-job", metavar="DIR")
    parser.add_argument("--verbose", action="store_true", help="print every test's output")
    parser.add_argument("--quick", action="store_true",
                        help="the quick tier's part of each test (the scripts that have one say "
                             "what it is); give it its own --out")
    parser.add_argument("--no-numeric", action="store_true",
                        help="leave out the version-independent numeric checks (scripts that have "
                             "them: test_scale, test_ringing, test_automatic)")
    parser.add_argument("tests", nargs="*")
    args = parser.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    zip_path = os.path.abspath(args.zip)
    blender = BlenderModule(args.bpy) if args.bpy else BlenderBinary(args.blender)

    if args.benchmark or args.main_job:
        name = "benchmark_viewport" if args.benchmark else "run_default_scene"
        target = out if args.benchmark else os.path.abspath(args.main_job)
        os.makedirs(target, exist_ok=True)
        code, seconds, text, log_path = run_one(blender, name, GPU if args.benchmark else BACKGROUND,
                                                1800, zip_path, out, target)
        lines = [l for l in text.splitlines() if not l.startswith(("EGL", "Info:", "Managed to", "# "))
                 and l.strip()]
        print("\n".join(lines))
        if code != 0:
            print("%s failed (exit %s); log: %s" % (name, code, log_path))
        return 0 if code == 0 else 1

    selected = [t for t in TESTS if not args.tests or t[0] in args.tests]
    unknown = set(args.tests) - {t[0] for t in TESTS}
    if unknown:
        parser.error("unknown tests: %s" % ", ".join(sorted(unknown)))
    print("%s (%s)" % (blender.label, blender.where), flush=True)
    failed, skipped = [], []
    for name, needs, limit, options, arguments, first_version in selected:
        reason = blender.skip_reason(needs)
        # A binary that cannot tell its version (0, 0, 0) is broken, not too old: it runs and fails.
        if reason is None and (0, 0, 0) < blender.version < first_version:
            reason = "needs Blender %d.%d+" % first_version[:2]
        if reason:
            print("%-24s SKIP  %s" % (name, reason), flush=True)
            skipped.append(name)
            continue
        code, seconds, text, log_path = run_one(blender, name, needs, limit, zip_path, out, options=options,
                                                arguments=list(arguments) + (["--quick"] if args.quick else [])
                                                + (["--no-numeric"] if args.no_numeric else []))
        summary = [l for l in text.splitlines() if l.startswith(name + ":")]
        ok = code == 0
        print("%-24s %s  %5.1f s  %s" % (name, "PASS" if ok else "FAIL", seconds,
                                         summary[-1] if summary else "(no summary; exit %s)" % code),
              flush=True)
        if not ok or args.verbose:
            for line in text.splitlines():
                if line.startswith(("[FAIL]", "Traceback", "  File", "    ")) or "Error" in line:
                    print("    " + line)
            print("    log: %s" % log_path)
        if not ok:
            failed.append(name)
    ran = len(selected) - len(skipped)
    print("blender tests (%s): %d passed, %d failed, %d skipped%s" % (
        blender.label, ran - len(failed), len(failed), len(skipped),
        (" (" + ", ".join(failed) + ")") if failed else ""))
    if failed:
        return 1
    return SKIPPED if selected and not ran else 0


if __name__ == "__main__":
    sys.exit(main())
