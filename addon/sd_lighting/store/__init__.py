"""What a bake leaves in the .blend: the baked meshes (baked.py), their `sd_` attributes
(attributes.py, laid out as bake_data.py says) and the bake record (record.py)."""
