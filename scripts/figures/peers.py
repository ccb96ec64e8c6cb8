"""The three surfaces of a zebra_peers figure: GERBS, Modified Butterfly, Catmull-Clark.

The peers are run by the same code as scripts/bench_shape.py (scripts/shape/methods.py):
MeshLab's Modified Butterfly through pymeshlab on the fan-triangulated cage (quads split
along the diagonal 0-2, n-gons into a fan from their first corner), and Blender's
Subdivision Surface modifier (Catmull-Clark, Blender's defaults), both at L steps.
"""
from __future__ import annotations

import bpy  # noqa: F401  (before pymeshlab, which shape.methods imports: their libraries clash)
import numpy as np

from figures import gerbs
from gerbs_core.testing import vertex_normals
from shape import methods


def matched_resolution(faces, n_vertices: int, counts, candidates=range(2, 33)) -> int:
    """The GERBS resolution whose output point count is closest (in log) to the
    geometric mean of the peers' point counts ``counts``."""
    target = float(np.mean(np.log(counts)))
    return min(candidates, key=lambda r: abs(np.log(gerbs.output_count(faces, n_vertices, r)) - target))


def zebra_surfaces(v, f, level: int):
    """[(caption, points (P,3), triangles (T,3), normals (P,3))] for GERBS | Butterfly |
    Catmull-Clark at matched output density.

    GERBS: the default BlendingSurface at :func:`matched_resolution`, normals exact (from
    its derivatives). Peers: ``level`` steps, normals angle-weighted averages of their
    output triangles' normals (:func:`gerbs_core.testing.vertex_normals`): what a smooth
    shaded subdivision mesh shows.
    """
    butterfly = methods.meshlab(v, f, "butterfly", level)
    catmull = methods.catmull_clark(bpy, v, f, level)
    r = matched_resolution(f, len(v), [len(butterfly["points"]), len(catmull["points"])])
    pts, tris, nrm = gerbs.tessellate(v, f, r)
    fanned = "" if all(len(face) == 3 for face in f) else ", fan-triangulated"
    out = [(f"GERBS, r = {r}\n{len(pts):,} vertices", pts, np.asarray(tris), nrm)]
    for caption, m in ((f"Modified Butterfly, {level} steps{fanned}", butterfly),
                       (f"Catmull-Clark, level {level}", catmull)):
        p, t = m["points"], m["triangles"]
        out.append((f"{caption}\n{len(p):,} vertices", p, t, vertex_normals(p, t)))
    return out
