"""The bake, in its three steps: prepare (main thread: prepare.py, the geometry: geometry.py, the
lightmap unwrap: unwrap.py), run (any thread: task.py - corner split: corners.py, refinement:
refine.py, rays, least squares: least_squares.py, texels: lightmap.py - in job.py's worker) and
store (main thread: job.py's apply, store/baked.py)."""
