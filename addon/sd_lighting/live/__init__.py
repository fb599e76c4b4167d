"""The live shading: the viewport's draw handler (drawing.py), its GPU programs and data
(gpu_shading.py, shader_variant.py), the lobe designs built for it (lobe_designs.py), still
previews (preview.py, gpu_context.py) and the Live Re-bake of edited objects (live_rebake.py,
rebake_schedule.py)."""
