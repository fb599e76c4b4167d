"""Every shader variant compiles: on this Blender's GPU backend, and under glslang's strictest
front end.

Variants: every method x lobes (Lambert, Phong, Lambert + Phong; PRT (2) Lambert only) x orders
(s, s') in ORDERS (0, 0 included: the smallest tables) x per-vertex / per-pixel x drawn /
vertex-target, the texture-space variants of the methods whose data texels hold (drawn, per
pixel), and the band-limited-texture variants of MSD (12), (13), and at ALBEDO_ORDERS each
drawn variant with material albedos (slots and an image texture; Lambert + Phong with the slots'
Principled weights, and Phong alone with them as a metal has; each of those also with the
prefiltered glossy light; Lambert with the weights and prefiltered light of rough dielectrics'
specular layers), and each drawn Lambert variant at ALBEDO_ORDERS also lit by SOURCES bright
sources with their shadow maps, each drawn prefiltered glossy one also with them and tracing its
visibility through the ray BVH (with and without the sources): N_VARIANTS programs, each built by
gpu_shading exactly as the live shading builds it (defines, frame block, samplers, interface).

1. GPU: gpu.shader.create_from_info on the running Blender (a GPU context from a Workbench render
   when headless). On bpy 4.2-5.0 and Debian's 3.4 headless this is OpenGL through Mesa (its GLSL
   compiler accepts implicit int -> float conversions, as GLSL 4.x allows): every variant. bpy 5.3
   defaults to Vulkan (Mesa's lavapipe): Blender's own GLSL -> SPIR-V front end, about 0.7 s a
   program; there one_per_layout's variants: each create-info's shape Blender's Vulkan backend
   lays out once (with its largest frame block), each #define once - the GLSL under every combination of #defines is what the OpenGL runs
   and step 2 compile. run.py gives every run fresh shader caches, so nothing comes from an
   earlier run.
2. Strict GLSL (on the Blender 5.0 run only - the sources do not depend on the Blender that runs
   the check -, when glslangValidator, Debian's glslang-tools, is installed): each stage's source,
   assembled the way Blender declares the create-info (version line, defines, the frame block,
   samplers, vertex inputs, interface, fragment output) before the add-on's GLSL, compiled by
   glslang as GLSL ES 3.20: no implicit conversions at all (an int where a float is expected, a
   float literal without a decimal point in float context, mixed int/float arithmetic are errors) -
   the rules the Metal backend's translation and the strictest drivers hold code to. (The Vulkan
   front end, glslang via shaderc, is step 1 on 5.3, which compiles every variant with it.)
--quick (the quick tier; the full tier on 4.2 and 4.5, whose Mesa GLSL compiler the 5.0 run
compiles every variant with): only the first variant to use each #define, sampler and vertex input.
Run: blender -b --factory-startup --python-exit-code 1 --python blender_tests/test_shader_variants.py -- --zip Z --out DIR [--quick]
"""

import importlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sdtest  # noqa: E402

import bpy  # noqa: E402

ORDERS = [(0, 0), (1, 1), (6, 3)]
ALBEDO_ORDERS = (1, 1)     # the albedo variants (colour per slot, image texture): at one order
N_VARIANTS = 700        # the programs variants() enumerates
LIGHTMAP = (1024, 512)     # texture-space variants: any size compiles the same way
PHONG_EXPONENT = 8.0
SOURCES = 4                # bright sources in the source variants (the most the map gives)


def _module(package, name):
    return importlib.import_module(package.__name__ + "." + name)


def variants(package):
    """Every variant the live shading can build at ORDERS, and at ALBEDO_ORDERS each drawn one of
    a Lambert lobe 0, or of a glossy one lit by the prefiltered atlas, also lit by SOURCES bright
    sources on their own; each such glossy one, or Lambert one with its specular layers, also
    tracing its visibility (reflection rays), with and without the sources."""
    import dataclasses
    rays = _module(package, "live.shader_variant").REFLECTION_RAYS
    for variant in _variants(package):
        yield variant
        if (not variant.vertex_target and (not variant.glossy or variant.prefiltered_lookup)
                and (variant.light_order, variant.visibility_order) == ALBEDO_ORDERS):
            yield dataclasses.replace(variant, sources=SOURCES)
            if variant.prefiltered_lookup:
                yield dataclasses.replace(variant, reflection_rays=rays)
                yield dataclasses.replace(variant, reflection_rays=rays, sources=SOURCES)


def _variants(package):
    shader_variant = _module(package, "live.shader_variant")
    sd = package.native.get()
    prefiltered_atlas = (sd.PREFILTER_WIDTH, sd.PREFILTER_LEVELS)
    for method in _module(package, "methods").METHODS:
        for glossy, both in (((False, False),) if method.lambert_only else
                             ((False, False), (True, False), (True, True))):
            for s, sv in ORDERS:
                stride = method.data.stride(s, sv) if method.data else 0
                design = diffuse_design = 0
                if method.lobe_design:  # the Gauss rule the live shading starts with: the largest
                    design = len(sd.zonal_design("phong" if glossy else "lambert", PHONG_EXPONENT,
                                                 s + sv, "gauss")[1])
                    if both:
                        diffuse_design = len(sd.zonal_design("lambert", 1.0, s + sv, "gauss")[1])
                lobes = {"lobe_weights": both, "diffuse_lobe": both, "diffuse_design_size": diffuse_design}
                gaunt = len(sd.gaunt_coefficients(s, sv, s + sv)[1]) if method.gaunt_table else 0
                textures = [()]
                if method.band_limited_texture:
                    textures.append(_module(package, "live.band_limited_map").texture_size(s))
                # with albedos (at ALBEDO_ORDERS): the lobes as they are, also with the prefiltered
                # light where weighted, and a Lambert lobe 0 with the specular layers of rough
                # dielectrics (weights and the prefiltered light)
                albedo_cases = [(lobes, ())] + ([(lobes, prefiltered_atlas)] if both else []) + \
                    ([({"lobe_weights": True}, prefiltered_atlas)] if not glossy else [])
                if _module(package, "bake.lightmap").applies(method):   # texture-space data
                    yield shader_variant.Variant(method, glossy, s, sv, stride, design, gaunt, True,
                                                 lightmap=LIGHTMAP, **lobes)
                    if (s, sv) == ALBEDO_ORDERS:
                        for weights, prefiltered in albedo_cases:
                            yield shader_variant.Variant(method, glossy, s, sv, stride, design, gaunt, True,
                                                         material_count=3, material_slots=True,
                                                         albedo_texture=True, lightmap=LIGHTMAP,
                                                         prefiltered=prefiltered, **weights)
                for per_pixel in (False, True):
                    for vertex_target in (False, True):
                        for texture in textures:
                            yield shader_variant.Variant(method, glossy, s, sv, stride, design, gaunt,
                                                         per_pixel, vertex_target, texture, **lobes)
                            if (s, sv) == ALBEDO_ORDERS and not vertex_target:
                                for weights, prefiltered in albedo_cases:
                                    yield shader_variant.Variant(
                                        method, glossy, s, sv, stride, design, gaunt, per_pixel,
                                        vertex_target, texture, material_count=3, material_slots=True,
                                        albedo_texture=True, prefiltered=prefiltered, **weights)
                                if glossy and not both:   # Principled metals: weights, one lobe
                                    for prefiltered in ((), prefiltered_atlas):
                                        yield shader_variant.Variant(
                                            method, glossy, s, sv, stride, design, gaunt, per_pixel,
                                            vertex_target, texture, material_count=3, material_slots=True,
                                            albedo_texture=True, lobe_weights=True, prefiltered=prefiltered)


def one_per_define(package, all_variants):
    """The quick tier's variants: the first to use each #define (by name), each sampler and each
    vertex input - every specialisation compiled once, about a tenth of the programs."""
    constants = package.native.get().sh_recurrence_constants
    seen, chosen = set(), []
    for variant in all_variants:
        features = (set(variant.defines(constants)) | {s for _, s in variant.samplers()}
                    | {a for _, a in variant.vertex_inputs()})
        if features - seen:
            seen |= features
            chosen.append(variant)
    return chosen


def one_per_layout(package, all_variants):
    """The Vulkan backend's variants: one_per_define's, and one with each create-info's shape - its
    samplers, vertex inputs, interface and frame block's fields, from which Blender's Vulkan
    backend lays out descriptor sets, push constants and locations -, the one whose frame block
    holds the most array elements (the arrays' lengths change offsets, not the layout's code;
    the largest block meets the backend's size limits; every length compiles under OpenGL and
    glslang)."""
    def elements(variant):
        return sum(int(n) for n in re.findall(r"\[(\d+)\]", variant.frame_struct()))

    largest = {}
    for variant in all_variants:
        shape = (tuple(variant.samplers()), tuple(variant.vertex_inputs()), tuple(variant.interface()),
                 re.sub(r"\[\d+\]", "[]", variant.frame_struct()))
        if shape not in largest or elements(variant) > elements(largest[shape]):
            largest[shape] = variant
    chosen = set(map(id, one_per_define(package, all_variants))) | set(map(id, largest.values()))
    return [variant for variant in all_variants if id(variant) in chosen]


def name(variant):
    return "%s%s%s s=%d s'=%d%s%s%s" % (
        variant.method.id, " phong" if variant.glossy else "",
        " +lambert" if variant.diffuse_lobe else "", variant.light_order,
        variant.visibility_order, " per-pixel" if variant.per_pixel else "",
        " vertex-target" if variant.vertex_target else "",
        " texture" if variant.band_limited_texture else "") + (" lightmap" if variant.lightmap else "") + (
        " %d sources" % variant.sources if variant.sources else "") + (
        " %d rays" % variant.reflection_rays if variant.reflection_rays else "")


# ----------------------------------------------------------------------------------------------
# The stage sources as Blender assembles them from the create-info (gpu_shading._compile).

ES_HEADER = ["#version 320 es", "precision highp float;", "precision highp int;",
             "precision highp sampler2D;"]


def stage_source(package, variant, stage):
    gs = package.live.gpu_shading
    lines = list(ES_HEADER)
    for key, value in variant.defines(package.native.get().sh_recurrence_constants).items():
        lines.append("#define %s %s" % (key, value))
    lines.append(variant.frame_struct())
    lines.append("layout(std140, binding = 0) uniform sd_block { SdFrameData sd; };")
    for slot, sampler in variant.samplers():
        lines.append("layout(binding = %d) uniform highp sampler2D %s;" % (slot, sampler))
    if stage == "vert":
        for location, (kind, attribute) in enumerate(variant.vertex_inputs()):
            lines.append("layout(location = %d) in %s %s;" % (location, kind, attribute))
    direction = "out" if stage == "vert" else "in"
    for location, (qualifier, kind, member) in enumerate(variant.interface()):
        lines.append("layout(location = %d) %s %s %s %s;" % (location, qualifier, direction, kind, member))
    if stage == "frag":
        lines.append("layout(location = 0) out vec4 fragColor;")
    vertex, fragment = gs.stage_sources(gs.SHADER_FILES)
    return "\n".join(lines) + "\n" + (vertex if stage == "vert" else fragment)


def background_stage_source(package, stage):
    """The world background's stage as gpu_shading._background_shader declares it (its push
    constants as a uniform block)."""
    gs = package.live.gpu_shading
    lines = ES_HEADER + ["#define SD_EQUIRECT_MAP %s" % gs.BACKGROUND_SAMPLER,
              "layout(std140, binding = 1) uniform sd_push { mat4 sd_inverse_view_projection; "
              "mat4 sd_to_environment; float sd_scale; };",
              "layout(binding = 0) uniform highp sampler2D %s;" % gs.BACKGROUND_SAMPLER]
    if stage == "vert":
        lines += ["layout(location = 0) in vec2 pos;", "layout(location = 0) smooth out vec2 sd_ndc;"]
    else:
        lines += ["layout(location = 0) smooth in vec2 sd_ndc;", "layout(location = 0) out vec4 fragColor;"]
    vertex, fragment = gs.stage_sources(gs.BACKGROUND_FILES)
    return "\n".join(lines) + "\n" + (vertex if stage == "vert" else fragment)


GLSLANG_BATCH = 40   # GLSL ES stage files per glslang process


def glslang_errors(validator, paths):
    """glslang's errors for each stage file of `paths` ([] where it accepts the file), each compiled
    on its own as GLSL ES, from one process for all of them: glslang sets up its built-in symbol
    tables once per process, most of a small compile's time. When the process fails, each file
    once more on its own says which fail and why."""
    def run(files):
        done = subprocess.run([validator] + list(files), capture_output=True, text=True, timeout=600)
        if done.returncode == 0:
            return []
        return [l for l in (done.stdout + done.stderr).splitlines()
                if "ERROR" in l and "compilation terminated" not in l] or [done.stdout + done.stderr]

    if not run(paths):
        return [[] for _ in paths]
    return [run([path]) for path in paths]


BACKGROUND = object()   # the world background's program, beside the variants in the glslang jobs


def main():
    checks = sdtest.Checks("test_shader_variants")
    args = sdtest.arguments()
    package = sdtest.install_addon(args.zip)
    package.live.gpu_context.ensure()
    import gpu
    backend = gpu.platform.backend_type_get() if hasattr(gpu.platform, "backend_type_get") else "OPENGL"
    print("GPU: %s, %s, %s" % (backend, gpu.platform.renderer_get(), gpu.platform.version_get()))
    all_variants = list(variants(package))
    checks.check(len(all_variants) == N_VARIANTS, "variants enumerated", "%d" % len(all_variants))
    if args.quick:
        all_variants = one_per_define(package, all_variants)
        print("quick: %d variants, one per #define, sampler and vertex input" % len(all_variants))
    elif backend == "VULKAN":
        all_variants = one_per_layout(package, all_variants)
        print("Vulkan: %d variants, one per create-info and #define" % len(all_variants))

    # 1. This Blender's GPU backend.
    failed, start = [], time.perf_counter()
    for variant in all_variants:
        try:
            package.live.gpu_shading.shader_program(variant)
        except Exception as exc:  # create_from_info raises with the compiler's log printed
            failed.append("%s: %s" % (name(variant), str(exc).splitlines()[0] if str(exc) else type(exc).__name__))
    checks.check(not failed, "every variant compiles on this Blender's GPU backend (%d programs, %.1f s)"
                 % (len(all_variants), time.perf_counter() - start), "; ".join(failed[:5]))
    try:
        package.live.gpu_shading._background_shader()
        problem = ""
    except Exception as exc:
        problem = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    checks.check(not problem, "the world background's shader compiles on this Blender's GPU backend", problem)
    package.live.gpu_shading.clear_cache()

    # 2. glslang, strict.
    validator = shutil.which("glslangValidator")
    if tuple(bpy.app.version[:2]) != (5, 0):
        print("strict GLSL checks run on the Blender 5.0 run only")
        return checks.summary()
    if validator is None:
        print("glslangValidator not found (Debian's glslang-tools): strict GLSL checks not run")
        return checks.summary()
    start = time.perf_counter()
    jobs = [(variant, stage) for variant in all_variants + [BACKGROUND] for stage in ("vert", "frag")]
    with tempfile.TemporaryDirectory() as directory, ThreadPoolExecutor(os.cpu_count() or 2) as pool:
        paths = []
        for index, (variant, stage) in enumerate(jobs):
            paths.append(os.path.join(directory, "%d.%s" % (index // 2, stage)))
            with open(paths[-1], "w", encoding="utf-8") as f:
                f.write(background_stage_source(package, stage) if variant is BACKGROUND
                        else stage_source(package, variant, stage))
        batches = [paths[i:i + GLSLANG_BATCH] for i in range(0, len(paths), GLSLANG_BATCH)]
        results = [errors for batch in pool.map(lambda batch: glslang_errors(validator, batch), batches)
                   for errors in batch]
        failed = ["%s %s: %s" % ("background" if variant is BACKGROUND else name(variant), stage,
                                 " | ".join(errors[:3]))
                  for (variant, stage), errors in zip(jobs, results) if errors]
    for line in failed[:10]:
        print("  " + line)
    checks.check(not failed, "glslang accepts every variant and the background as GLSL ES 3.20 (no implicit "
                 "conversions) (%.1f s)" % (time.perf_counter() - start),
                 "%d of %d stages fail; first: %s" % (len(failed), len(jobs), failed[0] if failed else ""))
    return checks.summary()


sdtest.run(main)
