"""What the scene gives the pipeline: the environment L and its rotation g (environment.py, with
the windows against ringing: ringing.py), the materials' lobes and albedos (materials.py,
lobes.py), cameras (view.py) and transforms (transforms.py)."""
