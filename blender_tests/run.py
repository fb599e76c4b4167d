#!/usr/bin/env python3
"""Runs the Blender tests of the add-on: each test script in its own Blender process, headless.

    python3 blender_tests/run.py --zip build/sd_lighting.zip --out build/blender_tests [TEST ...]

TEST names a test (test_bake, ...; default: all of TESTS, in order). Tests marked "xvfb" need a
window-system GPU context and run under `xvfb-run -a blender --factory-startup ...`; the others
run in `blender -b --factory-startup ...` (their GPU parts create a context through a Workbench
render). Every run gets its own BLENDER_USER_SCRIPTS/BLENDER_USER_CONFIG under --out, so
installing the zip never touches ~/.config/blender. Prints one line per test and a summary;
exits non-zero if any test fails.

`--benchmark` runs blender_tests/benchmark_viewport.py instead (prints the frame-time table).
`--main-job DIR` runs blender_tests/run_default_scene.py with --out DIR instead.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))

# (script, needs a window system, time limit in seconds, extra Blender options)
TESTS = [
    ("test_register", False, 120, []),
    ("test_bake", False, 300, []),
    ("test_gpu_matches_cpu", True, 600, []),
    ("test_preview", False, 300, []),
    ("test_world_orientation", False, 300, []),
    ("test_viewport", True, 600, ["--enable-event-simulate"]),
]


def blender_command(blender, script, xvfb, options, arguments):
    command = [blender]
    if xvfb:
        command = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24"] + command
    else:
        command.append("-b")
    return command + ["--factory-startup"] + list(options) + [
        "--python-exit-code", "1", "--python", os.path.join(HERE, script + ".py"), "--"] + arguments


def blender_environment(user):
    """The environment for Blender: its own user folders, and no trace of another Python (a pyenv
    interpreter running this script puts its bin/ first on PATH, and Blender - embedding the
    system's Python 3.11 - would then take that installation's prefix and miss Debian's numpy)."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("PYENV") and k not in ("PYTHONHOME", "PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = os.pathsep.join(p for p in os.environ.get("PATH", "").split(os.pathsep)
                                  if "/.pyenv/" not in p and "/virtualenvs/" not in p)
    env["BLENDER_USER_SCRIPTS"] = os.path.join(user, "scripts")
    env["BLENDER_USER_CONFIG"] = os.path.join(user, "config")
    return env


def run_one(blender, name, xvfb, limit, zip_path, out, script_out=None, options=()):
    """Runs one script; logs and Blender's user folders go under `out`, the script writes its
    files to `script_out` (default `out`)."""
    user = os.path.join(out, "blender_user", name)
    shutil.rmtree(user, ignore_errors=True)
    os.makedirs(user, exist_ok=True)
    env = blender_environment(user)
    command = blender_command(blender, name, xvfb, options, ["--zip", zip_path, "--out", script_out or out])
    log_path = os.path.join(out, name + ".log")
    start = time.perf_counter()
    with open(log_path, "w") as log:
        try:
            code = subprocess.run(command, env=env, stdout=log, stderr=subprocess.STDOUT,
                                  timeout=limit).returncode
        except subprocess.TimeoutExpired:
            code = "timeout"
    seconds = time.perf_counter() - start
    with open(log_path, errors="replace") as log:
        text = log.read()
    return code, seconds, text, log_path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--zip", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--blender", default=shutil.which("blender") or "/usr/bin/blender")
    parser.add_argument("--benchmark", action="store_true")
    parser.add_argument("--main-job", metavar="DIR")
    parser.add_argument("--verbose", action="store_true", help="print every test's output")
    parser.add_argument("tests", nargs="*")
    args = parser.parse_args()
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    zip_path = os.path.abspath(args.zip)

    if args.benchmark or args.main_job:
        name = "benchmark_viewport" if args.benchmark else "run_default_scene"
        target = out if args.benchmark else os.path.abspath(args.main_job)
        os.makedirs(target, exist_ok=True)
        code, seconds, text, log_path = run_one(args.blender, name, args.benchmark, 1800, zip_path, out,
                                                target)
        lines = [l for l in text.splitlines() if not l.startswith(("EGL", "Info:", "Managed to"))
                 and l.strip()]
        print("\n".join(lines))
        if code != 0:
            print("%s failed (exit %s); log: %s" % (name, code, log_path))
        return 0 if code == 0 else 1

    selected = [t for t in TESTS if not args.tests or t[0] in args.tests]
    unknown = set(args.tests) - {t[0] for t in TESTS}
    if unknown:
        parser.error("unknown tests: %s" % ", ".join(sorted(unknown)))
    failed = []
    for name, xvfb, limit, options in selected:
        code, seconds, text, log_path = run_one(args.blender, name, xvfb, limit, zip_path, out,
                                                options=options)
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
    print("blender tests: %d passed, %d failed%s" % (len(selected) - len(failed), len(failed),
                                                     (" (" + ", ".join(failed) + ")") if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
