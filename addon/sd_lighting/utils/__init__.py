"""The add-on's pure logic, free of bpy and gpu (like Blender's node_wrangler `utils/`): the method
table, the per-vertex data layout, the shader variants and their uniform block, lobes from
materials, rotations and transforms, the order limits. Tested without Blender by tests/addon/.
"""
