"""The sync refuses an input carrying a NaN or an infinite value (a UV, a color, any float
attribute, a vertex-group weight), as the core refuses such a position.

Why refuse rather than carry it: the result's record stores the input's values and the
node group shows the result only while every one equals the input's (node_fresh._differs:
NOT(|a - b| <= 0), which a NaN or an infinity never passes). A stored non-finite value
would leave the result stale for good, the base mesh shown with the "out of date"
warning while the sync reported success. Refused, the modifier shows the base mesh with
an error naming the layer and its first elements; nothing is written, and the next sync
after the value is made finite builds the surface.
"""
from __future__ import annotations

import numpy as np

from .errors import InvalidMeshError

PROBLEM = "non_finite_attribute"
ELEMENTS = {"POINT": "vertex", "EDGE": "edge", "FACE": "face", "CORNER": "corner"}


def plural(element: str) -> str:
    return "vertices" if element == "vertex" else element + "s"


def non_finite(inp):
    """An ``InvalidMeshError`` (problem ``PROBLEM``) naming the first carried layer of `inp`
    (mesh_io.MeshInput with carried) holding a NaN or an infinite value, or None.

    Its ``element`` is the layer's domain in words (``ELEMENTS``), ``indices`` the
    elements (rows of the layer's values (n, width)) with such a value, ``layer`` the
    layer's name; ``edges`` the (a, b) vertex pairs of an EDGE layer's edges and
    ``faces`` the faces of a CORNER layer's corners (what "Select the Problem" selects)."""
    for layer in inp.carried.layers:
        values = layer.values
        if values.dtype.kind != "f" or np.isfinite(values).all():
            continue
        bad = np.flatnonzero(~np.isfinite(values).all(axis=1))
        element = ELEMENTS[layer.domain]
        kind = "vertex group" if layer.group else "attribute"
        what = "" if layer.group else f" ({layer.domain} {layer.data_type})"
        exc = InvalidMeshError(PROBLEM, f'{PROBLEM}: NaN or infinite values of {kind} '
                                        f'"{layer.name}"{what} at {element} indices', bad, element)
        exc.layer = layer.name
        if layer.domain == "EDGE":
            exc.edges = [tuple(int(v) for v in inp.carried.edge_verts[e]) for e in bad]
        elif layer.domain == "CORNER":
            exc.faces = sorted(set(_face_of_loop(inp)[bad].tolist()))
        return exc
    return None


def _face_of_loop(inp) -> np.ndarray:
    """(C,) the face of each Blender loop (corner) of `inp`."""
    face = np.empty(len(inp.corners), dtype=np.int64)
    face[inp.loops()] = np.repeat(np.arange(len(inp.offsets) - 1), np.diff(inp.offsets))
    return face
