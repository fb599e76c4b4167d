"""Choosing a bake's settings before it runs: what each setting costs (cost.py) and takes
(bake_time.py), the error it would have (accuracy.py) and the automatic mode's choice
(automatic.py, analysis.py)."""
