"""Fillet sides: wide faces beside a turn of the cage concentrated near their edges (a
bevelled or rounded edge), where the tension keeps the surface near the cage.

A modeller rounds a box's edges with a bevel (Blender's Bevel modifier, 1-4 segments):
wide flat faces then meet through strips of much smaller faces that turn the cage by 90
degrees in steps of 22.5-45 degrees. No single edge turns as much as the tension's
sharpness threshold (:func:`gerbs_core.mesh.agreement.face_sharpness`, 50-80 degrees),
so without this rule no tension applies there, and the wide face's corners fit
local functions of degree 2 to stars that are flat on one side and turn sharply on the
other. A quadratic is even: it curves as much into the wide face as into the strip, and
every face balloons (bench_shape ``--only bevel``, r = 8: Blender's Cube with a Bevel of
width 0.2 in 1 / 2 / 4 segments 1.47 / 1.24 / 1.16 times the cage's box, Catmull-Clark
0.98-1.00; docs/design.md, "Fillet sides").

A convex face f (in its mean plane) is a fillet side when faces much smaller than f turn
against it close to its edges. A face g counts for the edge of f nearest to its centroid
(the segments' ends included) if that distance is at most ``REACH`` W_f (W_f the largest
distance from f's centroid to its corners: the turn is concentrated on the scale of f), its
size (square root of its area) is at most 1 / ``RATIO`` of f's and it is among the
``NEAREST`` such faces nearest to some edge's midpoint (bounded work); the angle between
their normals counts if it is at most ``TOP`` degrees (larger turns are spikes or
folds of the cage, not roundings: measured, counting them folded bunny10k's surface at
152 degrees); f is a fillet side if such turns of at least ``TURN_FROM`` degrees lie near
at least ``COVER`` of its edges (a face rounded on every side, as in a bevelled box;
measured, without it Suzanne's brow and ears counted too: her zebra stripes' small pieces
702 -> 720 and the cow's pairs above 90 degrees at r = 16 13 -> 30), with the weight the
smoothstep of the largest counted turn from ``TURN_FROM`` to ``TURN_TO`` degrees.
Non-convex faces are not fillet sides: their layout (the cyclic polygon of their edge
lengths) is far from them, and under the extra tension the inner L-shaped caps of an
extruded L with support loops folded (44 output pairs above 90 degrees at r = 8; 2
without them, where the fairing does not settle on that exact, symmetric input;
docs/design.md "Fillet sides").

Everything is read from the rest shape, so the surface stays a fixed linear function of
the positions. Smooth fine meshes (spheres, tori, height fields) and Blender's primitives
but the Monkey (2 faces) have no fillet side: their surfaces are bit-identical to those
without this rule. The weight is nearly always 0 or 1 (the cut-offs are hard): a switch,
not a ramp (docs/design.md, "Known limits").
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["REACH", "RATIO", "TURN_FROM", "TURN_TO", "TOP", "COVER", "NEAREST", "fillet_sides",
           "smoothstep"]

REACH = 0.25        # near: a smaller face's centroid within REACH W_f of an edge of f
RATIO = 3.0         # smaller: sqrt(area) at most 1 / RATIO of f's
TURN_FROM = 30.0    # degrees: the turns counted, and where the weight starts rising
TURN_TO = 45.0      # degrees: full weight
TOP = 100.0         # degrees: larger turns are not roundings and do not count
COVER = 0.5         # the least share of f's edges that such turns lie near
NEAREST = 32        # the candidate smaller faces per edge of f (the nearest to its midpoint)
TIE = 1e-9          # relative: edges within this of the nearest count as equally near (all)


def smoothstep(x, lo: float, hi: float) -> np.ndarray:
    """0 below ``lo``, 1 above ``hi``, 3 t^2 - 2 t^3 between (t = (x - lo) / (hi - lo)): the
    ramp of the tension's weights (these and :func:`gerbs_core.mesh.agreement.face_sharpness`)."""
    t = np.clip((x - lo) / (hi - lo), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def face_geometry(topo, X):
    """(centroids (F, 3), unit normals (F, 3), areas (F,), W (F,) the largest
    centroid-to-corner distances) of the faces at positions X (V, 3); normal and area from
    the vector area sum_k x_k x x_{k+1} / 2 (a non-planar face's mean plane)."""
    fv, cf, nx = topo.face_vertices, topo.corner_face, topo.corner_next
    sizes = np.asarray(topo.face_sizes, dtype=np.float64)
    cent = np.zeros((topo.n_faces, 3))
    np.add.at(cent, cf, X[fv])
    cent /= sizes[:, None]
    va = np.zeros((topo.n_faces, 3))
    np.add.at(va, cf, np.cross(X[fv] - cent[cf], X[fv[nx]] - cent[cf]))
    area = 0.5 * np.linalg.norm(va, axis=1)
    normal = va / np.maximum(2.0 * area, 1e-300)[:, None]
    W = np.zeros(topo.n_faces)
    np.maximum.at(W, cf, np.linalg.norm(X[fv] - cent[cf], axis=1))
    return cent, normal, area, W


def _convex(topo, X, normal) -> np.ndarray:
    """(F,) bool: the face turns the same way at every corner about its normal (a convex
    polygon in its mean plane; a straight corner counts as convex)."""
    fv, cf, nx, prev = topo.face_vertices, topo.corner_face, topo.corner_next, topo.corner_prev
    turn = (np.cross(X[fv] - X[fv[prev]], X[fv[nx]] - X[fv]) * normal[cf]).sum(1)
    scale = np.linalg.norm(X[fv] - X[fv[prev]], axis=1) * np.linalg.norm(X[fv[nx]] - X[fv], axis=1)
    bad = np.zeros(topo.n_faces, bool)
    bad[cf[turn < -1e-9 * scale]] = True
    return ~bad


def _near_pairs(topo, X, cent, W, size, eligible):
    """(f, g, k) (P,) each: for the ``eligible`` faces f (F,) bool of ``size`` (F,) (sqrt of
    the area) at least RATIO times the smallest face's, faces g of positive size at most
    1 / RATIO of f's whose centroid lies within REACH W_f of f's edges, k the corner of f
    starting the edge nearest to g's centroid (edge k: corner k -> next; the nearest point
    of the segment, its ends included).

    Bounded work: the candidates of an edge are the NEAREST smaller faces' centroids to its
    midpoint within half its length plus the reach (a KD-tree over the faces small enough
    for some f), so long thin faces beside many tiny ones cost O(edges x NEAREST), not
    O(faces^2) (a 4,000-segment Cylinder with short sides and fanned caps: 23 s and 4 GB
    with a ball query per face)."""
    empty = (np.empty(0, np.int64),) * 3
    positive = size > 0.0
    if not positive.any():
        return empty
    wide = eligible & (size >= RATIO * size[positive].min())
    if not wide.any():
        return empty
    small = np.flatnonzero(positive & (size * RATIO <= size[wide].max()))
    if not len(small):
        return empty
    fv, nx, cf, fo = topo.face_vertices, topo.corner_next, topo.corner_face, topo.face_offsets
    c = np.flatnonzero(wide[cf])                                # the wide faces' corners
    a, b = X[fv[c]], X[fv[nx[c]]]
    radius = 0.5 * np.linalg.norm(b - a, axis=1) + REACH * W[cf[c]]
    kq = min(NEAREST, len(small))
    dist, idx = cKDTree(cent[small]).query(0.5 * (a + b), k=kq,
                                           distance_upper_bound=float(radius.max()))
    dist, idx = dist.reshape(len(c), kq), idx.reshape(len(c), kq)
    hit = (idx < len(small)) & (dist <= radius[:, None])
    f = np.repeat(cf[c], kq).reshape(len(c), kq)[hit]
    g = small[idx[hit]]
    keep = size[g] * RATIO <= size[f]
    key = np.unique(f[keep] * topo.n_faces + g[keep])
    f, g = key // topo.n_faces, key % topo.n_faces
    sizes = np.asarray(topo.face_sizes)
    # every edge of f's distance to g's centroid (the nearest point of the segment, its
    # ends included), then every edge within TIE of the nearest: equally near edges (a
    # centroid beyond a corner is as near to both edges there; a symmetric cup's wall)
    # all count, so neither rounding nor where a face's corner list starts decides
    # (reviews, 2026-12-07: a 1e-12 scaling, a rotated corner list or a mirrored copy
    # moved a cup's surface by 0.26-0.56 of its height 2)
    kmax = int(sizes[f].max()) if len(f) else 0

    def distance(k):
        """(the pairs whose f has an edge k, their distances to it)"""
        at = np.flatnonzero(k < sizes[f])
        ck = fo[f[at]] + k
        a, ab = X[fv[ck]], X[fv[nx[ck]]] - X[fv[ck]]
        p = cent[g[at]] - a
        t = np.clip((p * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-300), 0.0, 1.0)
        return at, np.linalg.norm(p - t[:, None] * ab, axis=1)

    # two passes, O(pairs) memory (an n-gon of thousands of corners has as many edges)
    best = np.full(len(f), np.inf)
    for k in range(kmax):
        at, d = distance(k)
        best[at] = np.minimum(best[at], d)
    near = best <= REACH * W[f]
    rows, ks = [], []
    for k in range(kmax):
        at, d = distance(k)
        tie = near[at] & (d <= best[at] * (1.0 + TIE))
        rows.append(at[tie])
        ks.append(np.full(int(tie.sum()), k, np.int64))
    row = np.concatenate(rows) if rows else np.zeros(0, np.int64)
    k = np.concatenate(ks) if ks else np.zeros(0, np.int64)
    order = np.argsort(row, kind="stable")
    return f[row[order]], g[row[order]], k[order]


def fillet_sides(topo, X) -> np.ndarray:
    """(F,) in [0, 1]: how much each face is the wide side of a fillet at the rest positions
    X (V, 3) (module docstring): 0 for most faces of most meshes."""
    X = np.asarray(X, dtype=np.float64)
    cent, normal, area, W = face_geometry(topo, X)
    # a non-convex face's layout (the cyclic polygon of its edge lengths) is far from it:
    # measured, the inner L-shaped caps of an extruded L with support loops folded (44
    # output pairs above 90 degrees) under the fillet sides' tension
    f, g, k = _near_pairs(topo, X, cent, W, np.sqrt(area), _convex(topo, X, normal))
    ang = np.degrees(np.arccos(np.clip((normal[f] * normal[g]).sum(1), -1.0, 1.0)))
    ok = (ang >= TURN_FROM) & (ang <= TOP)
    f, k, ang = f[ok], k[ok], ang[ok]
    out = np.zeros(topo.n_faces)
    if not len(f):
        return out
    # the share of f's edges that such turns lie near (each edge (f, k) once)
    sizes = np.asarray(topo.face_sizes)
    m = int(sizes.max()) + 1
    edges = np.unique(f * m + k) // m
    covered = np.bincount(edges, minlength=topo.n_faces) >= COVER * sizes
    turn = np.zeros(topo.n_faces)
    np.maximum.at(turn, f, ang)
    out[covered] = smoothstep(turn[covered], TURN_FROM, TURN_TO)
    return out
