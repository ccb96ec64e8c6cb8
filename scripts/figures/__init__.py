"""Helpers of scripts/render_figures.py: scene set-up, materials, meshes, plots.

Not part of the installed package: documentation tooling only. The Blender
helpers (scene, materials, meshes) need the real ``bpy``; ``plots`` needs
matplotlib (the optional ``docs`` extra).
"""
