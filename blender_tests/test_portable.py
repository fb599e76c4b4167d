"""The zip on a system without Debian's Embree, TBB and OpenImageIO (issue 31): run by
blender_tests/hidden_libraries.sh inside a mount namespace where those files read as empty, on a
Blender as Python module (blender.org's builds carry their own libraries; Debian's Blender links
the hidden ones itself). SD_HIDDEN_LIBRARIES lists the hidden files; without it (a plain run) the
test still checks which libraries the add-on loaded.

- The extension zip installs, Blender installs its wheel, and the module loads the Embree that
  auditwheel grafted into the wheel (Blender
  4.2+ maps its own Embree 4 and OpenImageIO, which the module does not use; Debian's Blender 3.4
  loads the system's Embree 3 itself, so the test does not apply there).
- The default scene (Suzanne on a ground under forest.exr, an Environment Texture read by
  Blender: the module reads no files) bakes and previews.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_portable.py -- --zip Z --out DIR
"""

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402
import run_default_scene  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

OPTIONS = {"max_vertices": 2000, "hdri": "forest.exr", "width": 160, "height": 90, "exposure": -1.0,
           "cuts": 8, "subdivisions": 0}


def mapped_files():
    """The files this process has mapped (its shared objects among them)."""
    with open("/proc/self/maps") as maps:
        return {line.split(None, 5)[5].strip() for line in maps if len(line.split(None, 5)) == 6}


def main():
    checks = sdtest.Checks("test_portable")
    args = sdtest.arguments()
    hidden = [p for p in os.environ.get("SD_HIDDEN_LIBRARIES", "").split(":") if p]
    checks.check(all(os.path.getsize(p) == 0 for p in hidden),
                 "the system's Embree, TBB and OpenImageIO are hidden" if hidden else
                 "(a plain run: no library hidden)", ", ".join(hidden))
    package = sdtest.install_extension(args.zip)
    scene, _, monkey, ground = run_default_scene.build_scene(OPTIONS)
    checks.check(bpy.ops.sd_lighting.bake() == {'FINISHED'} and all("sd_bake" in o for o in (monkey, ground)),
                 "the default scene bakes")
    image = sdtest.preview(os.path.join(args.out, "portable.exr"))
    covered = image[..., 3] > 0.5
    checks.check(np.isfinite(image).all() and covered.mean() > 0.2 and image[covered][:, :3].max() > 0.05,
                 "and previews", "%.0f %% covered" % (100 * covered.mean()))

    # The wheel's package and auditwheel's folder of the libraries it grafted, beside it.
    folder = os.path.dirname(os.path.realpath(package.native.get().__file__))
    files = mapped_files()
    module = [f for f in files if os.path.basename(f).startswith("sdnative")]
    embree = [f for f in files if os.path.basename(f).startswith("libembree3")]   # Blender 4.2+ maps its own 4
    # both builds where the CPU runs x86-64-v3: native.py opens the portable one to ask cpuid
    checks.check(os.path.basename(folder) == package.native.WHEEL_PACKAGE and module and
                 all(os.path.dirname(os.path.realpath(f)) == folder for f in module) and
                 embree and all(os.path.dirname(os.path.realpath(f)) == folder + ".libs" for f in embree),
                 "the add-on's module runs on the Embree its wheel carries",
                 "%s; %s" % (module, embree))
    return checks.summary()


if __name__ == "__main__":
    sdtest.run(main)
