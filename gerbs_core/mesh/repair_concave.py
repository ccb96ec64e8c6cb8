"""Concave n-gons cut into convex faces (repair stage 3b, ``concave_face``).

Why: every face is laid out as a convex polygon (:func:`gerbs_core.mesh.layout.face_layouts`),
so on a concave face the blended local functions map a convex polygon onto a concave one
and the surface folds near the reflex corners. Found by a test with messy meshes
(2026-12-07, r = 4): a flat star-shaped 12-gon had 36 of its 192 output triangles
reversed, an L-shaped 12-gon 6, text with n-gon letters 3,529 of 10,480.

Which faces: ``MIN_CORNERS`` (5) or more corners whose corners turn back by more than
``REFLEX`` (10 degrees) in all, in the plane of their vector area. In all, not per corner:
a finely segmented concave curve turns back by less than 10 degrees at each corner (a half
annulus of 50 corners folded unsplit, 230 of 800 triangles reversed). Quads are kept: a
deformation makes quads concave far more often than a modeller draws one, and cutting
them would change the output's topology from frame to frame.

How: first the teeth (:func:`_teeth`: a run of convex corners between two reflex ones
that a chord cuts off as a convex piece: a gear's teeth, a star's points; a test with
concave n-gons found a 64-corner gear cut across into slivers, 162 of 1,120 output
triangles reversed, none now); then along diagonals until every corner of every piece is
below ``LIMIT`` (180 degrees less 1e-4 radians: straight corners are cut too); each cut
starts at such a corner and is
the diagonal resolving the most of them at its ends, then with the largest smallest angle
there (an L-shaped hexagon gives two quads); ties within ``_TIE`` go to the first corner,
so rounding cannot flip a symmetric face's cut; a chord that is already an edge of the
mesh is never cut (it would become non-manifold). No vertex is added; the pieces keep the
face's orientation and its input index (``face_map``), and the surface is C-infinity
across the new edges. Ear clipping followed by Hertel-Mehlhorn, tried first, gave pieces
of mixed shapes whose seams showed as ridges on an extruded star (rendered).

Limits (docs/design.md, mesh repair): the cuts follow the shape the surface is laid out
from, so in Follow mode a drag or an animation may change them and the output's topology;
very thin points still fold inside their own triangles (a 32-pointed star with inner
radius 0.5: 128 of 1,024 reversed).
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from .validation import corner_successors, face_vector_areas

REFLEX = math.radians(10.0)  # corners turning back by more than this in all: a concave face
# quads are kept: a deformation (a shape key, an armature, a drag) makes quads concave far
# more often than a modeller draws one, and their split would change the output's topology
# from frame to frame (two Blender tests' animated Suzanne had 11 such quads in a frame);
# concave n-gons are drawn (text, an extruded L, a boolean's or a dissolve's caps)
MIN_CORNERS = 5
# the largest corner a piece keeps: straight corners are cut too (a piece whose sides
# have collinear corners is laid out far from its shape: the L-shaped 12-gon cut in two
# with its midpoints still folded, 1 reversed output triangle at r = 4), but not the
# corners of a round cap (179 degrees made a review's 361-gon circle with a notch cut at
# every corner: 170 s)
LIMIT = math.pi - 1e-4
_TIE = 1e-6  # cuts whose smallest angles differ by less (radians) are equally good
# cuts are looked for from at most this many of the widest corners of a piece (with ties):
# a 400-corner star took 88 s looking from all of them, one cut at a time in Python
CANDIDATES = 8


def _turn(e1, e2) -> np.ndarray:
    """Signed turning angles from edge vectors e1 to e2 ((..., 2) arrays; positive: left)."""
    return np.arctan2(e1[..., 0] * e2[..., 1] - e1[..., 1] * e2[..., 0],
                      np.sum(e1 * e2, axis=-1))


def _turns(p2: np.ndarray) -> np.ndarray:
    """(n,) signed turning angle at each corner of the 2-d polygon p2 (n, 2) (positive:
    left turn, convex for a counter-clockwise polygon)."""
    return _turn(p2 - np.roll(p2, 1, axis=0), np.roll(p2, -1, axis=0) - p2)


def _angles(p2: np.ndarray) -> np.ndarray:
    """(n,) interior angles (radians, in (0, 2 pi)) of the counter-clockwise polygon p2."""
    return math.pi - _turns(p2)


def concave_faces(x, sizes, flat) -> np.ndarray:
    """(F,) bool: faces (CSR: corner counts `sizes`, vertices `flat`; positions x (V, 3))
    of at least ``MIN_CORNERS`` corners whose corners turn back by more than ``REFLEX`` in
    all about their vector area's normal."""
    sizes = np.asarray(sizes, dtype=np.int64)
    F = len(sizes)
    if not (sizes >= MIN_CORNERS).any():  # triangle and quad meshes: nothing to look at
        return np.zeros(F, dtype=bool)
    cf = np.repeat(np.arange(F), sizes)
    nxt = corner_successors(sizes)
    prv = np.empty_like(nxt)
    prv[nxt] = np.arange(len(nxt))
    normal = face_vector_areas(x, sizes, flat)  # (about each face's first corner: far from
    length = np.linalg.norm(normal, axis=1)  # the origin a review saw it 63 degrees off)
    normal /= np.where(length > 0, length, 1.0)[:, None]
    e1, e2 = x[flat] - x[flat[prv]], x[flat[nxt]] - x[flat]
    turn = np.arctan2(np.einsum("ij,ij->i", np.cross(e1, e2), normal[cf]),
                      np.einsum("ij,ij->i", e1, e2))
    back = np.zeros(F)  # the face's total turning back
    np.add.at(back, cf, np.minimum(turn, 0.0))
    return (back < -REFLEX) & (length > 0) & (sizes >= MIN_CORNERS)


def _plane(points: np.ndarray) -> np.ndarray:
    """(n, 2) coordinates of the face's corners (n, 3) in the plane of its vector area,
    counter-clockwise about it (about their mean: rounding far from the origin)."""
    points = points - points.mean(axis=0)
    normal = np.cross(points, np.roll(points, -1, axis=0)).sum(axis=0)
    normal /= np.linalg.norm(normal)
    u = points[1] - points[0]
    u -= (u @ normal) * normal
    u /= np.linalg.norm(u)
    return np.stack([points @ u, points @ np.cross(normal, u)], axis=1)


def _cross(o, a, b):
    """z of (a - o) x (b - o), broadcast over leading axes of (..., 2) arrays."""
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - \
        (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])


def _diagonals(P: np.ndarray, i: int) -> np.ndarray:
    """(m,) bool: corners j such that the segment from corner i to j is a diagonal of the
    counter-clockwise simple polygon P (m, 2): it leaves i into the polygon's interior
    angle and meets no side (nor passes through a corner) but at its ends."""
    m = len(P)
    j = np.arange(m)
    a, o, b = P[(i - 1) % m], P[i], P[(i + 1) % m]
    Q = P[j]
    if _cross(a, o, b) > 0:  # convex corner: strictly between the two sides
        cone = (_cross(o, Q, a) > 0) & (_cross(Q, o, b) > 0)
    else:  # reflex: not in the outside wedge
        cone = ~((_cross(o, Q, b) >= 0) & (_cross(Q, o, a) >= 0))
    s0, s1 = P, np.roll(P, -1, axis=0)  # sides k -> k + 1
    O, Qj = o[None, None], Q[:, None]
    d1, d2 = _cross(O, Qj, s0[None]), _cross(O, Qj, s1[None])
    d3, d4 = _cross(s0[None], s1[None], O), _cross(s0[None], s1[None], Qj)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)
    # a corner on the open segment (collinear, between the ends)
    t = np.einsum("jkc,jc->jk", P[None] - o, Q - o) / np.maximum(
        np.einsum("jc,jc->j", Q - o, Q - o), 1e-300)[:, None]
    on = (np.abs(_cross(O, Qj, P[None])) <= 1e-12 * np.einsum("jc,jc->j", Q - o, Q - o)[:, None]) \
        & (t > 0) & (t < 1)
    k = np.arange(m)
    touches = (k[None] == i) | (k[None] == j[:, None]) | ((k[None] + 1) % m == i) \
        | ((k[None] + 1) % m == j[:, None])
    blocked = ((proper & ~touches).any(axis=1)) | (on & (k[None] != i) & (k[None] != j[:, None])).any(axis=1)
    near = (j == i) | (j == (i + 1) % m) | (j == (i - 1) % m)
    return cone & ~blocked & ~near


def _interior(prev, at, nxt) -> np.ndarray:
    """Interior angles (radians, in (0, 2 pi)) at corners `at` of counter-clockwise
    polygons, between their neighbours `prev` and `nxt` ((..., 2) arrays)."""
    return math.pi - _turn(at - prev, nxt - at)


def _best_cut(P: np.ndarray, wide, taken=frozenset()) -> tuple | None:
    """(i, j) the diagonal that splits P best: from a corner i of more than ``LIMIT``,
    resolving the most such ends (both pieces below ``LIMIT`` there), then with the
    largest smallest angle at its ends in the two pieces (no slivers); of the cuts within
    ``_TIE`` of the best, the first (i, then j, ascending). `taken`: corner pairs (i, j),
    i < j, that may not be cut (edges the mesh has already). None where no diagonal exists
    (P not simple). Vectorized over j: O(len(wide) m^2) for m corners."""
    m = len(P)
    here = _angles(P) > LIMIT
    cuts, keys = [], []
    for i in wide:
        j = np.flatnonzero(_diagonals(P, i))
        if taken:
            j = np.array([k for k in j.tolist() if (min(i, k), max(i, k)) not in taken],
                         dtype=np.int64)
        if not len(j):
            continue
        pi, pj = P[i], P[j]
        # the two pieces: A = i, i + 1, ..., j and B = j, j + 1, ..., i
        a_i = _interior(pj, pi, P[(i + 1) % m])
        a_j = _interior(P[(j - 1) % m], pj, pi)
        b_j = _interior(pi, pj, P[(j + 1) % m])
        b_i = _interior(P[(i - 1) % m], pi, pj)
        resolved = (np.maximum(a_i, b_i) <= LIMIT).astype(int) + \
            (here[j] & (np.maximum(a_j, b_j) <= LIMIT))
        smallest = np.minimum(np.minimum(a_i, a_j), np.minimum(b_i, b_j))
        cuts += [(i, int(k)) for k in j]
        keys.append(np.stack([resolved, smallest], axis=1))
    if not cuts:
        return None
    keys = np.concatenate(keys)
    best = keys[:, 0] == keys[:, 0].max()
    good = best & (keys[:, 1] >= keys[best, 1].max() - _TIE)
    return cuts[int(np.flatnonzero(good)[0])]


def _teeth(P: np.ndarray, taken) -> list:
    """Chords (a, b) between consecutive reflex corners a, b of the counter-clockwise
    polygon P (m, 2) that cut off a convex "tooth" a, a + 1, ..., b (the teeth of a gear, the
    points of a star), each a diagonal not in `taken`."""
    m = len(P)
    reflex = np.flatnonzero(_angles(P) > math.pi + REFLEX / 10).tolist()
    cuts = []
    for a, b in zip(reflex, reflex[1:] + reflex[:1]):
        if (b - a) % m < 2 or a == b or (min(a, b), max(a, b)) in taken \
                or not _diagonals(P, a)[b]:
            continue
        tooth = [k % m for k in range(a, a + (b - a) % m + 1)]
        if (_angles(P[tooth]) < LIMIT).all():
            cuts.append((a, b))
    return cuts


def convex_pieces(p2: np.ndarray, taken=frozenset()) -> list:
    """Pieces (lists of local corner indices, counter-clockwise) covering the simple
    polygon p2 (n, 2), cut along diagonals between its corners until every corner of
    every piece is below ``LIMIT``: each cut starts at a corner above it and is chosen by
    :func:`_best_cut`, never along a pair of `taken` (corner index pairs (a, b), a < b:
    edges the mesh has already, which a cut would make non-manifold); a piece with no
    diagonal left (p2 not simple in its plane, or every diagonal taken) is kept as it is,
    so a face that cannot be cut comes back whole."""
    todo, out = [list(range(len(p2)))], []
    teeth = _teeth(p2, taken)  # first the teeth (a gear's, a star's), then the rest
    if teeth:
        m = len(p2)
        out = [[k % m for k in range(a, a + (b - a) % m + 1)] for a, b in teeth]
        cut = {a: b for a, b in teeth}
        rest, k = [], min(a for a, _ in teeth)
        while True:
            rest.append(k)
            k = cut.get(k, (k + 1) % m)
            if k == rest[0]:
                break
        todo = [rest] if len(rest) >= 3 else []
    while todo:
        poly = todo.pop()
        P = p2[poly]
        angle = _angles(P)
        wide = np.flatnonzero(angle > LIMIT).tolist()
        if not wide or len(poly) == 3:  # (a triangle is convex: a near-straight one stays)
            out.append(poly)
            continue
        if len(wide) > CANDIDATES:  # the widest (ties by corner order): O(m^2) a cut
            cut_at = np.sort(angle[wide])[-CANDIDATES] - _TIE
            wide = [k for k in wide if angle[k] >= cut_at][:CANDIDATES]
        where = {c: k for k, c in enumerate(poly)}
        cut = _best_cut(P, wide, frozenset((min(where[a], where[b]), max(where[a], where[b]))
                                           for a, b in taken if a in where and b in where))
        if cut is None:  # not simple in this plane: kept as it is
            out.append(poly)
            continue
        i, j = cut
        m = len(poly)
        todo.append([poly[k % m] for k in range(i, i + ((j - i) % m) + 1)])
        todo.append([poly[k % m] for k in range(j, j + ((i - j) % m) + 1)])
    return sorted(out, key=min)


def split_concave(x, sizes, flat, origin, notes):
    """Stage 3b: replace each concave face (:func:`concave_faces`) by its convex pieces
    (:func:`convex_pieces` in the face's plane); (sizes, flat, origin) of the new faces,
    the pieces in place of their face. A face that is not simple in its plane is kept."""
    if not len(sizes):  # every face was degenerate (refused as empty after this stage)
        return sizes, flat, origin
    concave = concave_faces(x, sizes, flat)
    if not concave.any():
        return sizes, flat, origin
    offsets = np.r_[0, np.cumsum(sizes)]
    nxt = flat[corner_successors(sizes)]
    near = defaultdict(set)  # each vertex's neighbours along the mesh's edges
    for a, b in zip(flat.tolist(), nxt.tolist()):
        near[a].add(b)
        near[b].add(a)
    new_faces, new_origin, split = [], [], []
    for f in range(len(sizes)):
        face = flat[offsets[f]:offsets[f + 1]].tolist()
        pieces = []
        if concave[f]:
            # a chord that is already an edge of the mesh (a face on it): not cut (a
            # review: the cut made that edge non-manifold)
            at = {v: k for k, v in enumerate(face)}
            taken = frozenset((min(at[a], at[b]), max(at[a], at[b])) for a in face
                              for b in near[a] if b in at)
            pieces = convex_pieces(_plane(x[face]), taken)
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
