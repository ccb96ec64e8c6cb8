"""The map of lattice samples into their faces' polygons (:meth:`Lattice.map_to_polygon`,
:meth:`Lattice.corner_weights` of :mod:`gerbs_core.mesh.lattice`).

Triangles barycentric, quads bilinear, n-gons barycentric in the fan triangle (centre,
corner k, corner k+1): exact affine/bilinear formulas, evaluated vectorized.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["corner_weights", "map_to_polygon", "map_points"]


def _params(lat, local: bool):
    """(face, fan, uv) of the samples, or of the local table with `local`."""
    if local:
        return lat.local_face, lat.local_fan, lat.local_uv
    return lat.face, lat.fan, lat.uv


def corner_weights(lat, local: bool = False, rows=None) -> np.ndarray:
    """(P, n_max) weights of each sample's face corners (:meth:`Lattice.corner_weights`);
    `rows`: only those samples, as wide as their largest face."""
    tp = lat.topology
    face, fan, uv = _params(lat, local)
    if rows is not None:
        face, fan, uv = face[rows], fan[rows], uv[rows]
    n = tp.face_sizes[face]
    a, b = uv[:, 0], uv[:, 1]
    width = int(tp.face_sizes.max()) if rows is None else int(n.max(initial=0))
    w = np.zeros((len(face), width))
    s = n == 3
    if s.any():
        w[s, 0], w[s, 1], w[s, 2] = 1 - a[s] - b[s], a[s], b[s]
    s = n == 4
    if s.any():
        w[s, 0], w[s, 1] = (1 - a[s]) * (1 - b[s]), a[s] * (1 - b[s])
        w[s, 2], w[s, 3] = a[s] * b[s], (1 - a[s]) * b[s]
    s = np.flatnonzero(n >= 5)
    if len(s):
        w[s] = ((1 - a[s] - b[s]) / n[s])[:, None] * (np.arange(w.shape[1]) < n[s][:, None])
        w[s, fan[s]] += a[s]
        w[s, (fan[s] + 1) % n[s]] += b[s]
    return w


def _fan_centres(tp, X, centers):
    """(F, d) fan centres: the corners' mean, or the given ones (checked)."""
    if centers is None:
        return np.add.reduceat(X, tp.face_offsets[:-1], axis=0) / tp.face_sizes[:, None]
    ctr = np.asarray(centers, dtype=np.float64)
    if ctr.shape != (tp.n_faces, X.shape[1]):
        raise InvalidParameterError("centers", f"must have shape ({tp.n_faces}, "
                                    f"{X.shape[1]}), got {ctr.shape}")
    return ctr


def map_to_polygon(lat, corners2d, centers=None, local: bool = False) -> np.ndarray:
    """(P, d) (or (L, d)) samples mapped into the polygons of the corner coordinates
    ``corners2d`` (C, d) (:meth:`Lattice.map_to_polygon`)."""
    tp = lat.topology
    X = np.asarray(corners2d, dtype=np.float64)
    if X.ndim != 2 or X.shape[0] != tp.n_corners:
        raise InvalidParameterError("corners2d", f"must have shape ({tp.n_corners}, d), got "
                                    f"{X.shape}")
    ctr = _fan_centres(tp, X, centers) if centers is not None else None  # checked always
    return map_points(tp, X, *_params(lat, local), ctr)


def map_points(tp, X, face, fan, uv, ctr=None) -> np.ndarray:
    """(N, d) points of parameters (face (N,), fan (N,), uv (N, 2)) (those of
    :mod:`gerbs_core.mesh.lattice`) in the polygons of the corner coordinates X (C, d);
    ctr (F, d) the n-gons' fan centres (default the corners' mean). The same formulas
    for any points: a template point of a face maps as that face's lattice sample."""
    fo, n = tp.face_offsets[face], tp.face_sizes[face]
    a, b = uv[:, :1], uv[:, 1:]
    out = np.empty((len(face), X.shape[1]))
    for size, s in _by_size(n):
        aa, bb, c = a[s], b[s], fo[s]
        if size == 3:
            out[s] = (1 - aa - bb) * X[c] + aa * X[c + 1] + bb * X[c + 2]
        elif size == 4:
            out[s] = ((1 - aa) * (1 - bb) * X[c] + aa * (1 - bb) * X[c + 1]
                      + aa * bb * X[c + 2] + (1 - aa) * bb * X[c + 3])
        else:
            if ctr is None:
                ctr = _fan_centres(tp, X, None)
            k = fan[s]
            c0 = c + k
            c1 = c + (k + 1) % n[s]
            out[s] = (1 - aa - bb) * ctr[face[s]] + aa * X[c0] + bb * X[c1]
    return out


def _by_size(n):
    """(size, selector) of the samples by face size n (P,): 3, 4 and >= 5 (the fans, one
    group); the selector a full slice when every sample has it (no masked copies)."""
    groups = [(3, n == 3), (4, n == 4), (5, n >= 5)]
    for size, s in groups:
        if s.all():
            return [(size, slice(None))]
    return [(size, s) for size, s in groups if s.any()]
