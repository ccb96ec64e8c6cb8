"""Blender's creases for the surface: ``crease_edge`` (edge float attribute, 0..1) and
``crease_vert`` (point float attribute, 0..1), read without touching the user's mesh.

Read from the mesh data-block's *evaluated* copy (``obj.data.evaluated_get(depsgraph)``)
or, in Edit Mode, from the edit BMesh's float layers (BMesh elements stay where they are):
never from the original mesh's attributes (a Python read of those un-shares the arrays
the evaluated copy shares and invalidates the references the user holds, issue 12; the
same rule as :mod:`blender_addon.mesh_io`). The creases belong to the vertices of that
data-block; when a modifier above GERBS changes the vertex count they no longer match
what the modifier receives and are ignored (logged).

The core takes them as ``BlendingSurface(..., creases=(edges (K, 2), weights (K,)),
corners=(V,) weights)`` (:mod:`gerbs_core.mesh.crease_surface`). :attr:`Creases.key` goes
into the engine's settings key, so a crease change rebuilds without the Rebuild operator
and a position change with the same creases takes the stencil's fast path.
"""
from __future__ import annotations

import hashlib
import logging
from dataclasses import dataclass

import numpy as np

log = logging.getLogger(__name__)

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


def _float_attribute(mesh, name, domain, n):
    attr = mesh.attributes.get(name)
    if attr is None or attr.domain != domain or attr.data_type != "FLOAT" or n == 0:
        return None
    buf = np.empty(n, dtype=np.float32)
    attr.data.foreach_get("value", buf)
    return buf


def read_mesh(mesh) -> Creases:
    """The creases of an evaluated (or add-on-owned) mesh."""
    E, V = len(mesh.edges), len(mesh.vertices)
    edge_w = _float_attribute(mesh, EDGE_ATTRIBUTE, "EDGE", E)
    vert_w = _float_attribute(mesh, VERTEX_ATTRIBUTE, "POINT", V)
    if edge_w is None and vert_w is None:
        return NONE
    pairs = np.empty(2 * E, dtype=np.int32)
    mesh.edges.foreach_get("vertices", pairs)
    return _pack(pairs.reshape(-1, 2), np.zeros(E, np.float32) if edge_w is None else edge_w,
                 vert_w)


def read_edit_mesh(mesh) -> Creases:
    """The creases of an original mesh in Edit Mode, through its BMesh's float layers."""
    import bmesh

    bm = bmesh.from_edit_mesh(mesh)
    el = bm.edges.layers.float.get(EDGE_ATTRIBUTE)
    vl = bm.verts.layers.float.get(VERTEX_ATTRIBUTE)
    if el is None and vl is None:
        return NONE
    bm.verts.index_update()
    pairs = np.array([(e.verts[0].index, e.verts[1].index) for e in bm.edges],
                     dtype=np.int32).reshape(-1, 2)
    edge_w = np.array([e[el] for e in bm.edges] if el is not None else np.zeros(len(pairs)),
                      dtype=np.float32)
    vert_w = None if vl is None else np.array([v[vl] for v in bm.verts], dtype=np.float32)
    return _pack(pairs, edge_w, vert_w)


def read(obj, depsgraph, n_vertices: int) -> Creases:
    """The creases of `obj`'s mesh for a modifier receiving ``n_vertices`` vertices."""
    if obj.mode == "EDIT":
        out = read_edit_mesh(obj.data)
        count = len(obj.data.vertices) if out.vertex is None else len(out.vertex)
    else:
        mesh = obj.data.evaluated_get(depsgraph)
        out = read_mesh(mesh)
        count = len(mesh.vertices)
    if out.any and count != n_vertices:
        log.info("GERBS: %s: creases ignored (a modifier above changes the vertices: %d -> %d)",
                 obj.name, count, n_vertices)
        return NONE
    return out
