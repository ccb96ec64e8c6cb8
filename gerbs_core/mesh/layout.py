"""Face layouts: a planar convex reference polygon D_f for every face (the domain).

Every face f with n corners gets the *cyclic* polygon with f's 3D edge lengths
in the rest shape the surface is bound to. Shared edges then have equal lengths
on both sides, so neighbouring faces glue isometrically, which is what makes
the vertex charts (:mod:`gerbs_core.mesh.charts`) consistent, and the layouts
follow the geometry: a topology-only layout (every face a unit regular polygon,
the original design's default) measured 5.5x too tall on Blender's Cylinder,
whose 2-unit side quads and radius-1 caps it would draw at the same size.

Frame of D_f ("face local coordinates"): corner 0 at the origin, edge 0 (corner 0
-> corner 1) along +x, corners counter-clockwise. Triangles are placed exactly
(law of cosines); n-gons (n >= 4) by solving for the circumradius R with
bisection on t = L / (2R) (L the longest edge) to full double precision, both in
the centred case (sum of half central angles = pi) and in the non-centred case
(the centre lies outside, beyond the longest edge: the other half angles sum to
the longest edge's half angle).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InvalidMeshError
from .validation import not_a_polygon

__all__ = ["FaceLayouts", "face_layouts", "cyclic_polygon"]


@dataclass(frozen=True)
class FaceLayouts:
    """Reference polygons of all faces, stored per corner (CSR like the topology).

    Attributes (C = number of corners = sum of face sizes):
      corners (C, 2): corner positions in their face's local frame.
      angles (C,): interior angle of D_f at each corner (radians, in (0, pi)).
      lengths (C,): length of the edge from each corner to the next one of its face.
    """

    corners: np.ndarray
    angles: np.ndarray
    lengths: np.ndarray


def _cyclic_triangle(lengths: np.ndarray) -> np.ndarray:
    """Triangles (F, 3, 2) with edge lengths (F, 3) by the law of cosines (exact)."""
    l0, l1, l2 = lengths[:, 0], lengths[:, 1], lengths[:, 2]
    x = (l0 * l0 + l2 * l2 - l1 * l1) / (2.0 * l0)
    y = np.sqrt(np.maximum(l2 * l2 - x * x, 0.0))
    out = np.zeros((len(lengths), 3, 2))
    out[:, 1, 0] = l0
    out[:, 2, 0] = x
    out[:, 2, 1] = y
    return out


def _circumradius(lengths: np.ndarray):
    """(R (F,), imax (F,), centred (F,)): the circumradius of the cyclic polygons with
    edge lengths (F, n), their longest edge, and whether the centre lies inside.

    Bisection on t = L / (2R) to full double precision (at most 64 halvings)."""
    F, n = lengths.shape
    imax = np.argmax(lengths, axis=1)
    L = lengths[np.arange(F), imax]
    rel = lengths / L[:, None]  # in (0, 1]
    others = np.ones((F, n), dtype=bool)
    others[np.arange(F), imax] = False
    relo = np.where(others, rel, 0.0)
    # centred iff at R = L/2 (t = 1) the other half-angles already reach pi/2
    centred = np.sum(np.arcsin(relo), axis=1) >= 0.5 * np.pi
    lo = np.zeros(F)
    hi = np.ones(F)
    # f(t) = sum_others asin(t r_i) -/+ ... ; both branches are increasing in t
    #   centred:     sum_others asin(t r_i) + asin(t) - pi  (root in (0, 1])
    #   non-centred: sum_others asin(t r_i) - asin(t)       (root in (0, 1))
    for _ in range(64):
        t = 0.5 * (lo + hi)
        s = np.sum(np.arcsin(t[:, None] * relo), axis=1)
        f = np.where(centred, s + np.arcsin(t) - np.pi, s - np.arcsin(t))
        if np.all(hi - lo <= 4e-16):
            break
        # centred: f increasing in t; non-centred: f < 0 near t=1, > 0 near t=0
        go_left = np.where(centred, f > 0, f < 0)
        hi = np.where(go_left, t, hi)
        lo = np.where(go_left, lo, t)
    t = 0.5 * (lo + hi)
    return L / (2.0 * t), imax, centred


def _to_face_frame(pts: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """Polygons (F, n, 2) moved to the face frame: corner 0 at the origin, edge 0 along
    +x (its end set exactly to (length, 0))."""
    pts = pts - pts[:, :1, :]
    e0 = pts[:, 1, :]
    c, s = e0[:, 0] / lengths[:, 0], e0[:, 1] / lengths[:, 0]
    x = c[:, None] * pts[..., 0] + s[:, None] * pts[..., 1]
    y = -s[:, None] * pts[..., 0] + c[:, None] * pts[..., 1]
    out = np.stack([x, y], axis=-1)
    out[:, 0, :] = 0.0
    out[:, 1, :] = [0.0, 0.0]
    out[:, 1, 0] = lengths[:, 0]
    return out


def cyclic_polygon(lengths: np.ndarray) -> np.ndarray:
    """Cyclic convex polygons with given edge lengths, vectorized over polygons.

    lengths (F, n), n >= 3, edge i from corner i to corner i+1; every edge shorter than
    the sum of the others (:func:`face_layouts` checks). Returns corners (F, n, 2) in
    the face frame (corner 0 at the origin, edge 0 along +x, ccw). Exact for
    triangles; n-gons to ~1e-15 relative.
    """
    lengths = np.asarray(lengths, dtype=np.float64)
    F, n = lengths.shape
    if n == 3:
        return _cyclic_triangle(lengths)
    R, imax, centred = _circumradius(lengths)
    half = np.arcsin(np.clip(lengths / (2.0 * R[:, None]), -1.0, 1.0))
    arcs = 2.0 * half
    # the longest edge goes back along the short arc when the centre is outside
    arcs[np.arange(F), imax] = np.where(centred, arcs[np.arange(F), imax],
                                        -arcs[np.arange(F), imax])
    ang = np.concatenate([np.zeros((F, 1)), np.cumsum(arcs[:, :-1], axis=1)], axis=1)
    pts = R[:, None, None] * np.stack([np.cos(ang), np.sin(ang)], axis=-1)
    return _to_face_frame(pts, lengths)


def _corner_angles(corners: np.ndarray) -> np.ndarray:
    """Interior angles (F, n) of ccw convex polygons (F, n, 2)."""
    nxt = np.roll(corners, -1, axis=1) - corners
    prv = np.roll(corners, 1, axis=1) - corners
    cross = nxt[..., 0] * prv[..., 1] - nxt[..., 1] * prv[..., 0]
    dot = np.sum(nxt * prv, axis=-1)
    return np.arctan2(cross, dot)


def face_layouts(topo, positions: np.ndarray) -> FaceLayouts:
    """Reference polygons D_f of all faces: cyclic polygons with the edge lengths of
    `positions` (V, 3), the rest shape the surface is bound to.

    Raises InvalidMeshError("degenerate_face") naming the faces whose edge lengths admit
    no convex polygon (some edge >= sum of the others, or zero length).
    """
    off, fv, sizes = topo.face_offsets, topo.face_vertices, topo.face_sizes
    P = np.asarray(positions, dtype=np.float64)
    lengths = np.linalg.norm(P[fv[topo.corner_next]] - P[fv], axis=1)
    corners = np.zeros((len(fv), 2))
    angles = np.zeros(len(fv))
    bad = []
    for n in np.unique(sizes):
        fs = np.nonzero(sizes == n)[0]
        idx = off[fs][:, None] + np.arange(n)[None, :]
        ln = lengths[idx]
        lmax = ln.max(axis=1)
        degenerate = (ln.min(axis=1) <= 0) | not_a_polygon(lmax, ln.sum(axis=1))
        if np.any(degenerate):
            bad.extend(fs[degenerate].tolist())
            continue
        pts = cyclic_polygon(ln)
        corners[idx] = pts
        angles[idx] = _corner_angles(pts)
    if bad:
        raise InvalidMeshError("degenerate_face",
                               "faces whose edge lengths admit no convex polygon "
                               "(an edge is not shorter than the sum of the others)",
                               sorted(bad), "face")
    for a in (corners, angles, lengths):
        a.flags.writeable = False
    return FaceLayouts(corners, angles, lengths)
