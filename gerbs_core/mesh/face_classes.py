"""Faces whose stencil rows are equal bit for bit: the assembly evaluates each class once.

A sample's row values (Psi_k and Psi_k mono_m of its face's corners k, :mod:`.assembly`)
are elementwise functions of its template point and of its face's per-corner data:
the layout corners, the charts (theta0, beta, alpha, the vertex's scale), the cover's
envelope of the corner (index and angle offset; the spoke caps' sector values where
the cover has them), the vertex's degree, and the corners' order by vertex (the terms'
order in the row). Faces equal in all of these bits are one *class*: the values at a
template point are the same in every face of the class, so they are computed for one
representative face and copied (a regular grid's 4096 faces are 60 classes; Suzanne's
500 faces 500: there the assembly evaluates every sample as before).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["FaceClasses", "face_classes"]


class FaceClasses(NamedTuple):
    """Per size class of the lattice (same order): ``cls`` (nf,) the class of each face,
    ``rep`` (K,) the representative face of each class (the first face of it)."""

    cls: tuple
    rep: tuple


def _corner_bits(model, by_vertex) -> np.ndarray:
    """(C, k) uint64: every per-corner input of a row's values, as bits."""
    topo, ch, cover = model.topology, model.charts, model.cover
    v = topo.face_vertices
    rank = np.empty(topo.n_corners, dtype=np.int64)
    rank[by_vertex] = np.arange(topo.n_corners) - topo.face_offsets[topo.corner_face[by_vertex]]
    cols = [model.layouts.corners[:, 0], model.layouts.corners[:, 1], ch.origin[:, 0],
            ch.origin[:, 1], ch.theta0, ch.beta, ch.alpha, ch.scale[v], cover.env_offset]
    ints = [cover.corner_env, np.asarray(model.degrees)[v], rank]
    caps = cover.caps
    if caps is not None:
        cols += [caps.Ua, caps.Ub, caps.ta, caps.tb]
    f = np.column_stack([np.asarray(c, dtype=np.float64) for c in cols]).view(np.uint64)
    i = np.column_stack([np.asarray(c, dtype=np.int64) for c in ints]).view(np.uint64)
    return np.hstack([f, i])


def face_classes(model, lattice, by_vertex) -> FaceClasses:
    """The classes of the faces of every size class of ``lattice`` (bits of
    :func:`_corner_bits` of all its corners, in corner order)."""
    bits = _corner_bits(model, by_vertex)
    fo = model.topology.face_offsets
    cls, rep = [], []
    for fk, _, _, n in lattice.size_classes:
        rows = bits[fo[fk][:, None] + np.arange(n)].reshape(len(fk), -1)
        key = np.ascontiguousarray(rows).view(np.dtype((np.void, rows.shape[1] * 8))).ravel()
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        cls.append(inverse.ravel())
        rep.append(fk[first])
    return FaceClasses(tuple(cls), tuple(rep))
