"""Helpers of scripts/bench_shape.py: the inputs (inputs.py), the methods compared
(methods.py: MeshLab's Butterfly and Loop, Blender's Catmull-Clark, the GERBS
adapter and its variant registry), the measurements (measure.py, on top of
gerbs_core.testing) and the table and acceptance verdicts (report.py)."""
