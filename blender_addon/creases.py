"""Blender's creases for the surface: ``crease_edge`` (edge float attribute, 0..1) and
``crease_vert`` (point float attribute, 0..1), taken from what the modifier receives.

They are carried layers like any other (blender_addon/attributes.py reads them from the
evaluated mesh the stack delivers, or the Edit Mode BMesh's copy, never from the user's
original mesh, issue 12), so modifiers above GERBS bring their creases along and a
result's record holds them: :func:`from_carried`.

The core takes them as ``BlendingSurface(..., creases=(edges (K, 2), weights (K,)),
corners=(V,) weights)`` (:mod:`gerbs_core.mesh.crease_surface`). :attr:`Creases.key` goes
into the engine's settings key, so a crease change rebuilds without the Rebuild operator
and a position change with the same creases takes the stencil's fast path.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np

EDGE_ATTRIBUTE = "crease_edge"
VERTEX_ATTRIBUTE = "crease_vert"


@dataclass(frozen=True, eq=False)
class Creases:
    """Crease weights of one mesh: ``edges`` (K, 2) int32 vertex pairs of the edges with a
    weight > 0, ``weights`` (K,) float32, ``vertex`` (V,) float32 or None (all zero)."""

    edges: np.ndarray
    weights: np.ndarray
    vertex: np.ndarray | None

    @property
    def any(self) -> bool:
        return len(self.weights) > 0 or self.vertex is not None

    @property
    def key(self) -> str:
        """A digest of the weights (equal creases, equal key)."""
        if not self.any:
            return ""
        h = hashlib.blake2b(digest_size=16)
        for a in (self.edges, self.weights) + (() if self.vertex is None else (self.vertex,)):
            h.update(np.ascontiguousarray(a).tobytes())
            h.update(b"|")
        return h.hexdigest()

    def core_arguments(self) -> dict:
        """Keyword arguments of gerbs_core's BlendingSurface."""
        return {"creases": (self.edges, self.weights) if len(self.weights) else None,
                "corners": self.vertex}


NONE = Creases(np.zeros((0, 2), np.int32), np.zeros(0, np.float32), None)


def _pack(pairs, edge_w, vert_w) -> Creases:
    keep = edge_w > 0.0
    vertex = vert_w if vert_w is not None and np.any(vert_w > 0.0) else None
    return Creases(np.ascontiguousarray(pairs[keep], dtype=np.int32),
                   np.ascontiguousarray(edge_w[keep], dtype=np.float32), vertex)


def _face_edges(offsets, corners, pairs) -> np.ndarray:
    """(K,) bool: which vertex pairs (K, 2) are edges of a face (CSR faces)."""
    offsets = np.asarray(offsets, dtype=np.int64)
    a = np.asarray(corners, dtype=np.int64)
    p = np.asarray(pairs, dtype=np.int64)
    nxt = np.arange(1, len(a) + 1)
    nxt[offsets[1:] - 1] = offsets[:-1]                 # each face's last corner -> its first
    b = a[nxt] if len(a) else a
    n = int(max(a.max(initial=-1), p.max(initial=-1))) + 1
    keys = np.minimum(a, b) * n + np.maximum(a, b)
    return np.isin(np.minimum(p[:, 0], p[:, 1]) * n + np.maximum(p[:, 0], p[:, 1]), keys)


def from_carried(carried, offsets=None, corners=None) -> Creases:
    """The creases among the layers the modifier receives (:class:`blender_addon.attributes.
    Carried`: read from what the stack delivers, so modifiers above GERBS that change the
    mesh bring their creases along, and a result's record holds them too). With the input's
    faces (``offsets`` (F+1,), ``corners`` (C,)), the creases of loose edges (in no face:
    not part of the surface, as their vertices are not) are left out: the core refuses
    creases on pairs that are not edges of its faces (a stress test: Select All and Shift+E
    on a mesh with a wire edge stopped the whole surface)."""
    if carried is None:
        return NONE
    layers = {(layer.name, layer.domain, layer.data_type): layer for layer in carried.layers
              if not layer.group}
    edge = layers.get((EDGE_ATTRIBUTE, "EDGE", "FLOAT"))
    vert = layers.get((VERTEX_ATTRIBUTE, "POINT", "FLOAT"))
    if edge is None and vert is None:
        return NONE
    pairs = np.asarray(carried.edge_verts, dtype=np.int32).reshape(-1, 2)
    edge_w = np.zeros(len(pairs), np.float32) if edge is None else edge.values[:, 0]
    if offsets is not None and np.any(edge_w > 0.0):
        edge_w = np.where(_face_edges(offsets, corners, pairs), edge_w, np.float32(0.0))
    return _pack(pairs, edge_w, None if vert is None else vert.values[:, 0])
