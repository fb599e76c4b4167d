"""The user interface: settings (properties.py, limits.py), operators (operators.py), the sidebar
panel (panels.py) and the bake-time prediction it shows (prediction.py)."""
