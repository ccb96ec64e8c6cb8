"""Concave faces split into convex ones (repair stage 3b, ``concave_face``).

Every face is laid out as a convex polygon (:func:`gerbs_core.mesh.layout.face_layouts`),
so on a face with a reflex corner the blended local functions map a convex polygon onto
a concave one, and the surface folds near that corner. Found by a test with messy meshes
(2026-12-07, r = 4): a flat star-shaped 12-gon had 36 of its 192 output triangles
reversed, an L-shaped 12-gon 6, and text converted to a mesh with n-gon letters 75% of its
area; a flat dart quad folds from a reflex angle of about 20 degrees (r = 8: 3 reversed
triangles at 20, 57 at 90; none at 10).

A face with a corner turning back by more than ``REFLEX`` (10 degrees) in the plane of
its vector area is split along diagonals into convex pieces: ear clipping (at each step
the ear whose smallest angle is largest), then Hertel-Mehlhorn (a diagonal is removed
again wherever both of its ends stay convex, so a concave quad gives two triangles and
an L-shaped hexagon two quads). No vertex is added; the pieces keep the face's
orientation and its input index (``face_map``), and the surface is C-infinity across the
new edges. Faces turning back by less (Suzanne has two quads at 1 degree) are kept.
"""
from __future__ import annotations

import math

import numpy as np

from .validation import corner_successors

REFLEX = math.radians(10.0)  # a corner turning back by more than this makes a face concave
_STRAIGHT = 1e-9  # |turn| below this (radians) counts as a straight corner: still convex
_TIE = 1e-6  # ears whose smallest angles differ by less (radians) are equally good


def _turns(p2: np.ndarray) -> np.ndarray:
    """(n,) signed turning angle at each corner of the 2-d polygon p2 (n, 2) (positive:
    left turn, convex for a counter-clockwise polygon)."""
    e1 = p2 - np.roll(p2, 1, axis=0)
    e2 = np.roll(p2, -1, axis=0) - p2
    cross = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    return np.arctan2(cross, np.sum(e1 * e2, axis=1))


def concave_faces(x, sizes, flat) -> np.ndarray:
    """(F,) bool: faces (CSR: corner counts `sizes`, vertices `flat`; positions x (V, 3))
    with a corner turning back by more than ``REFLEX`` about their vector area's normal."""
    sizes = np.asarray(sizes, dtype=np.int64)
    F = len(sizes)
    cf = np.repeat(np.arange(F), sizes)
    nxt = flat[corner_successors(sizes)]
    p, q = x[flat], x[nxt]
    normal = np.zeros((F, 3))
    np.add.at(normal, cf, np.cross(p, q))
    length = np.linalg.norm(normal, axis=1)
    normal /= np.where(length > 0, length, 1.0)[:, None]
    first = np.r_[0, np.cumsum(sizes)[:-1]]
    prv_corner = np.arange(len(flat)) - 1
    prv_corner[first] += sizes  # the first corner's predecessor is the face's last
    e1 = p - x[flat[prv_corner]]
    e2 = q - p
    turn = np.arctan2(np.einsum("ij,ij->i", np.cross(e1, e2), normal[cf]),
                      np.einsum("ij,ij->i", e1, e2))
    worst = np.full(F, np.inf)
    np.minimum.at(worst, cf, turn)
    return (worst < -REFLEX) & (length > 0)


def _plane(points: np.ndarray) -> np.ndarray:
    """(n, 2) coordinates of the face's corners (n, 3) in the plane of its vector area,
    counter-clockwise about it."""
    normal = np.cross(points, np.roll(points, -1, axis=0)).sum(axis=0)
    normal /= np.linalg.norm(normal)
    u = points[1] - points[0]
    u -= (u @ normal) * normal
    u /= np.linalg.norm(u)
    return np.stack([points @ u, points @ np.cross(normal, u)], axis=1)


def _inside(tri: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(m,) bool: points (m, 2) inside or on the counter-clockwise triangle (3, 2)."""
    out = np.ones(len(pts), dtype=bool)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        d = tri[b] - tri[a]
        out &= d[0] * (pts[:, 1] - tri[a, 1]) - d[1] * (pts[:, 0] - tri[a, 0]) >= 0
    return out


def _ears(p2: np.ndarray) -> list:
    """Triangles (local corner index triples, counter-clockwise) of the simple polygon p2
    (n, 2), by ear clipping, the ear with the largest smallest angle first."""
    ring = list(range(len(p2)))
    tris = []
    while len(ring) > 3:
        P = p2[ring]
        turn = _turns(P)
        best, best_angle = None, -1.0
        for k in np.flatnonzero(turn > _STRAIGHT):
            i, j = (k - 1) % len(ring), (k + 1) % len(ring)
            others = np.ones(len(ring), dtype=bool)
            others[[i, k, j]] = False
            if _inside(P[[i, k, j]], P[others]).any():
                continue
            a, b, c = P[i], P[k], P[j]
            angles = [abs(math.atan2(np.cross(v - u, w - u), np.dot(v - u, w - u)))
                      for u, v, w in ((a, b, c), (b, c, a), (c, a, b))]
            if min(angles) > best_angle + _TIE:  # ties go to the first corner: a split
                best, best_angle = k, min(angles)  # that rounding cannot change
        if best is None:  # not a simple polygon in this plane: no ear to cut
            return []
        n = len(ring)
        tris.append([ring[(best - 1) % n], ring[best], ring[(best + 1) % n]])
        del ring[best]
    return tris + [ring]


def _merge(a: list, b: list, u: int, v: int) -> list:
    """The polygon of `a` (with the edge u -> v) and `b` (with v -> u) without that edge."""
    i, j = a.index(v), b.index(u)
    a, b = a[i:] + a[:i], b[j:] + b[:j]  # a = [v, ..., u], b = [u, ..., v]
    return a + b[1:-1]


def convex_pieces(p2: np.ndarray) -> list:
    """Convex polygons (lists of local corner indices, counter-clockwise) covering the
    simple polygon p2 (n, 2) with diagonals between its corners (Hertel-Mehlhorn over an
    ear clipping: at most four times the fewest pieces); [] where p2 is not simple."""
    pieces = [list(t) for t in _ears(p2)]
    if not pieces:
        return []
    n = len(p2)
    changed = True
    while changed:
        changed = False
        edges = {}
        for k, poly in enumerate(pieces):
            for s, t in zip(poly, poly[1:] + poly[:1]):
                edges[(s, t)] = k
        for (s, t), k in edges.items():
            if (t - s) % n in (1, n - 1):  # a side of the face, not a diagonal
                continue
            m = edges.get((t, s))
            if m is None or m == k:
                continue
            merged = _merge(pieces[k], pieces[m], s, t)
            turn = _turns(p2[merged])
            if turn[0] > _STRAIGHT and turn[merged.index(s)] > _STRAIGHT:  # at t and s
                pieces[k] = merged
                del pieces[m]
                changed = True
                break
    return pieces


def split_concave(x, sizes, flat, origin, notes):
    """Stage 3b: replace each concave face (:func:`concave_faces`) by its convex pieces
    (:func:`convex_pieces` in the face's plane); (sizes, flat, origin) of the new faces,
    the pieces in place of their face. A face that is not simple in its plane is kept."""
    concave = concave_faces(x, sizes, flat)
    if not concave.any():
        return sizes, flat, origin
    offsets = np.r_[0, np.cumsum(sizes)]
    new_faces, new_origin, split = [], [], []
    for f in range(len(sizes)):
        face = flat[offsets[f]:offsets[f + 1]].tolist()
        pieces = convex_pieces(_plane(x[face])) if concave[f] else []
        if len(pieces) > 1:
            split.append(origin[f])
            new_faces += [[face[i] for i in piece] for piece in pieces]
            new_origin += [origin[f]] * len(pieces)
        else:
            new_faces.append(face)
            new_origin.append(origin[f])
    if split:
        notes.append(("concave_face", np.unique(split), "face", None))
    sizes = np.array([len(f) for f in new_faces], dtype=np.int64)
    return sizes, np.concatenate(new_faces).astype(flat.dtype), np.asarray(new_origin)
