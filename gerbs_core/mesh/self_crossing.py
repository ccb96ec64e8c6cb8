"""A warning where the surface passes through itself (a cup's wall or floor).

Where a part of the cage is thin against its faces, the local functions of its two sides
bulge into each other: a cup (a Cylinder of 16 sides, its top inset by 0.12 and extruded
down 1.75, no loop cuts) comes out with its walls, floor and bottom crossing (425 pairs of
output triangles at r = 4, none with Subdivision Surface; a modelling session, 2026-12-07,
found a mug and a table crossing too, 533 and 34 pairs, until the fillet rule's ties
counted every equally near edge). The box of such a surface stays near the cage's, so the
thin-part warning (:mod:`gerbs_core.mesh.thin_parts`) does not see it; this check does.

It reads the surface on the same lattice as the thin-part check (resolution 4, 2 on large
meshes): triangles of that lattice that cross, sharing no point, by a segment longer than
``MIN_OVERLAP`` of the pair's longest edge (so triangles that only touch, as the fans of
a non-manifold vertex do at their common point, do not count). Exact for those triangles;
a crossing thinner than them may be missed (a warning, not a proof). Not blamed on the
surface (:func:`surface_crossings`): crossings between faces that share a position (a fold
of neighbours), those the cage has itself nearby (Suzanne's eyes pass through her head),
and those next to a position of several vertices (a bow-tie's fans, an open seam).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .arrays import ranges
from .repair import MeshWarning

__all__ = ["crossing_pairs", "surface_crossings", "self_crossing_warning", "MIN_OVERLAP",
           "MAX_PAIRS"]

MIN_OVERLAP = 1e-3   # a crossing segment shorter than this x the pair's longest edge: touching
MAX_PAIRS = 4_000_000  # candidate pairs at most (else no warning: too dense to tell cheaply)
CHUNK = 250_000       # candidate pairs tested at once (~60 MB of temporaries)


def _interval(P, d, line):
    """(lo, hi) (K,) of the segment where triangles P (K, 3, 3) meet a plane, projected on
    `line` (K, 3); d (K, 3) the corners' signed distances to that plane (a corner at 0 is
    on it). Every triangle given reaches the plane."""
    proj = np.einsum("kcj,kj->kc", P, line)                        # (K, 3)
    lo = np.where(d == 0.0, proj, np.inf).min(axis=1)
    hi = np.where(d == 0.0, proj, -np.inf).max(axis=1)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        cut = d[:, i] * d[:, j] < 0.0
        s = d[:, i] / np.where(cut, d[:, i] - d[:, j], 1.0)
        t = proj[:, i] + s * (proj[:, j] - proj[:, i])
        lo = np.where(cut, np.minimum(lo, t), lo)
        hi = np.where(cut, np.maximum(hi, t), hi)
    return lo, hi


def _test(P, A, B, scale):
    """(K,) bool: do triangles A and B (index arrays into P (T, 3, 3)) cross by more than
    MIN_OVERLAP x scale (K,)?"""
    TA, TB = P[A], P[B]
    nA = np.cross(TA[:, 1] - TA[:, 0], TA[:, 2] - TA[:, 0])
    nB = np.cross(TB[:, 1] - TB[:, 0], TB[:, 2] - TB[:, 0])
    # signed distances (times |n|) of each triangle's corners to the other's plane, with
    # those within rounding of it put on it
    dB = np.einsum("kcj,kj->kc", TB - TA[:, :1], nA)
    dA = np.einsum("kcj,kj->kc", TA - TB[:, :1], nB)
    tolB = 1e-12 * np.linalg.norm(nA, axis=1)[:, None] * scale[:, None]
    tolA = 1e-12 * np.linalg.norm(nB, axis=1)[:, None] * scale[:, None]
    dB = np.where(np.abs(dB) <= tolB, 0.0, dB)
    dA = np.where(np.abs(dA) <= tolA, 0.0, dA)
    reach = ((dB.min(1) <= 0) & (dB.max(1) >= 0) & (dA.min(1) <= 0) & (dA.max(1) >= 0)
             & ~((dB == 0).all(1)))                      # coplanar pairs: not counted
    out = np.zeros(len(A), bool)
    k = np.flatnonzero(reach)
    if not len(k):
        return out
    line = np.cross(nA[k], nB[k])
    ln = np.linalg.norm(line, axis=1)
    ok = ln > 1e-12 * np.linalg.norm(nA[k], axis=1) * np.linalg.norm(nB[k], axis=1)
    line = line / np.maximum(ln, 1e-300)[:, None]
    a0, a1 = _interval(TA[k], dA[k], line)
    b0, b1 = _interval(TB[k], dB[k], line)
    overlap = np.minimum(a1, b1) - np.maximum(a0, b0)
    out[k] = ok & (overlap > MIN_OVERLAP * scale[k])
    return out


def _candidates(c, radius):
    """(K, 2) pairs (i < j) of triangles whose bounding spheres (centres c (T, 3), radii
    (T,)) may meet, or None where there are more than MAX_PAIRS. Triangles are grouped by
    size (powers of 2), so a few large ones (an n-gon's fan) do not widen every query."""
    level = np.floor(np.log2(radius / max(float(radius.min()), 1e-300))).astype(np.int64)
    groups = [np.flatnonzero(level == L) for L in np.unique(level)]
    trees = [cKDTree(c[g]) for g in groups]
    top = [float(radius[g].max()) for g in groups]
    parts, total = [], 0
    for a, (ga, ta) in enumerate(zip(groups, trees)):
        for b in range(a, len(groups)):
            r = top[a] + top[b]
            if a == b:
                ij = ta.query_pairs(r, output_type="ndarray")
                i, j = ga[ij[:, 0]], ga[ij[:, 1]]
            else:
                m = ta.sparse_distance_matrix(trees[b], r, output_type="ndarray")
                i, j = ga[m["i"]], groups[b][m["j"]]
            total += len(i)
            if total > MAX_PAIRS:
                return None
            parts.append(np.stack([np.minimum(i, j), np.maximum(i, j)], axis=1))
    return np.concatenate(parts) if parts else np.zeros((0, 2), np.int64)


def crossing_pairs(points, triangles, pairs=None) -> np.ndarray | None:
    """(K, 2) int64 the pairs (i < j) of triangles (T, 3) of points (N, 3) that share no
    point index and cross (module docstring); ``pairs`` (K', 2): only these candidates (else
    every pair whose bounding spheres meet); None where those are more than MAX_PAIRS."""
    X = np.asarray(points, dtype=np.float64)
    T = np.asarray(triangles, dtype=np.int64)
    if len(T) < 2:
        return np.zeros((0, 2), np.int64)
    if pairs is None:
        return _crossings(X, T, None)
    # only the triangles named: solved on those, indices mapped back
    used, local = np.unique(np.asarray(pairs, dtype=np.int64), return_inverse=True)
    if len(used) < 2:
        return np.zeros((0, 2), np.int64)
    out = _crossings(X, T[used], local.reshape(-1, 2))
    return None if out is None else used[out]


def _crossings(X, T, pairs):
    """:func:`crossing_pairs` of every triangle of T (pairs None: found here)."""
    P = X[T]                                                          # (T, 3, 3)
    c = P.mean(axis=1)
    radius = np.linalg.norm(P - c[:, None], axis=2).max(axis=1)
    edge = np.linalg.norm(P - np.roll(P, 1, axis=1), axis=2).max(axis=1)
    if not np.isfinite(radius).all():
        return None
    pairs = _candidates(c, np.maximum(radius, 1e-300)) if pairs is None else pairs
    if pairs is None:
        return None
    lo, hi = P.min(axis=1), P.max(axis=1)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    found = []
    for s in range(0, len(pairs), CHUNK):   # bounded temporaries
        A, B = pairs[s:s + CHUNK].T
        # boxes first: long thin triangles' spheres overlap nearly all (a review: a pole
        # of 72 sides, 3.6M candidate pairs of which 73k boxes meet)
        near = (lo[A] <= hi[B]).all(axis=1) & (lo[B] <= hi[A]).all(axis=1)
        A, B = A[near], B[near]
        shared = (T[A][:, :, None] == T[B][:, None, :]).any(axis=(1, 2))
        A, B = A[~shared], B[~shared]
        hit = _test(P, A, B, np.maximum(edge[A], edge[B]))
        found.append(np.stack([np.minimum(A[hit], B[hit]), np.maximum(A[hit], B[hit])], axis=1))
    out = np.concatenate(found) if found else np.zeros((0, 2), np.int64)
    return out[np.lexsort((out[:, 1], out[:, 0]))]


def _face_spheres(points, groups, n):
    """(centres (n, 3), radii (n,)) bounding the points of each group (groups (k,) the
    group of each point, points (k, 3))."""
    count = np.maximum(np.bincount(groups, minlength=n), 1)
    centre = np.stack([np.bincount(groups, points[:, j], minlength=n) for j in range(3)],
                      axis=1) / count[:, None]
    radius = np.zeros(n)
    np.maximum.at(radius, groups, np.linalg.norm(points - centre[groups], axis=1))
    return centre, radius


def _position_ids(topology, cage) -> np.ndarray:
    """(V,) a group id per vertex: vertices closer than ``SEAM_RTOL`` median edge lengths
    share one (the repair's rule for an open seam), so a seam whose copies differ by
    rounding (a mirror without clipping, a float32 round trip) counts as one place (a
    review: copies 1e-9 apart warned on 42 faces along Suzanne's detached half)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from .repair import SEAM_RTOL

    X = np.asarray(cage, dtype=np.float64)
    e = np.asarray(topology.edges)
    scale = float(np.median(np.linalg.norm(X[e[:, 0]] - X[e[:, 1]], axis=1))) if len(e) else 0.0
    pairs = cKDTree(X).query_pairs(SEAM_RTOL * scale, output_type="ndarray") \
        if scale > 0 else np.zeros((0, 2), np.int64)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                       shape=(len(X), len(X)))
    return connected_components(graph, directed=False)[1]


def _incidence(topology, pid):
    """Sparse (P, F) incidence of the cage's distinct positions (``pid`` (V,):
    :func:`_position_ids`) and the faces: faces that share a position are neighbours, also
    where the repair split a vertex into one per fan (a bow-tie) or an export left a seam
    open (coincident vertices): their surfaces meet there as drawn."""
    from scipy.sparse import csr_matrix
    fv = np.asarray(topology.face_vertices)
    return csr_matrix((np.ones(len(fv), np.int32), (pid[fv], np.asarray(topology.corner_face))),
                      shape=(int(pid.max()) + 1, topology.n_faces))


def _apart(inc, fa, fb) -> np.ndarray:
    """(K,) bool: faces fa and fb (K,) share no position (``inc``: :func:`_incidence`)."""
    adjacent = (inc.T @ inc).tocoo()                                  # faces sharing one
    n = np.int64(inc.shape[1])
    keys = adjacent.row.astype(np.int64) * n + adjacent.col
    return ~np.isin(np.asarray(fa, np.int64) * n + np.asarray(fb, np.int64), keys)


def _fan(topology, faces):
    """(triangles (t, 3) of the cage's faces ``faces``, fanned from their first corner;
    (t,) their face)."""
    fo, fv = np.asarray(topology.face_offsets), np.asarray(topology.face_vertices)
    n = np.asarray(topology.face_sizes)[faces] - 2          # triangles per face
    owner = np.repeat(faces, n)
    second = ranges(fo[faces] + 1, n)                        # corners 1 .. size - 2
    return np.stack([fv[fo[owner]], fv[second], fv[second + 1]], axis=1), owner


def surface_crossings(topology, cage, points, triangles, triangle_face):
    """(K, 2) the pairs of ``triangles`` (T, 3) of the surface's ``points`` (N, 3) that
    cross where the cage does not: of faces (``triangle_face`` (T,), faces of ``topology``)
    that share no position, and not both near (sharing a position with) faces of the cage
    (``cage`` (V, 3), the faces fanned) that cross each other (Suzanne's eyes pass through
    her head: so does her surface, as drawn). None where too dense to tell."""
    T = np.asarray(triangles, dtype=np.int64)
    tf = np.asarray(triangle_face, dtype=np.int64)
    F = topology.n_faces
    X = np.asarray(points, dtype=np.float64)
    centre, radius = _face_spheres(X[T].reshape(-1, 3), np.repeat(tf, 3), F)
    fpairs = _candidates(centre, np.maximum(radius, 1e-300))
    if fpairs is None:
        return None
    fa, fb = fpairs[:, 0], fpairs[:, 1]
    near = np.linalg.norm(centre[fa] - centre[fb], axis=1) <= radius[fa] + radius[fb]
    fa, fb = fa[near], fb[near]
    pid = _position_ids(topology, cage)
    inc = _incidence(topology, pid)
    keep = _apart(inc, fa, fb)
    fa, fb = fa[keep], fb[keep]
    if not len(fa):
        return np.zeros((0, 2), np.int64)
    # the triangle pairs of those face pairs: of each face, the triangles whose boxes meet
    # the other face's box (the rest cannot cross it), then every pair of those
    P = X[T]
    tlo, thi = P.min(axis=1), P.max(axis=1)
    flo = np.full((F, 3), np.inf)
    fhi = np.full((F, 3), -np.inf)
    np.minimum.at(flo, tf, tlo)
    np.maximum.at(fhi, tf, thi)
    meet = (flo[fa] <= fhi[fb]).all(axis=1) & (flo[fb] <= fhi[fa]).all(axis=1)
    fa, fb = fa[meet], fb[meet]
    order = np.argsort(tf, kind="stable")
    start = np.searchsorted(tf[order], np.arange(F + 1))
    size = start[1:] - start[:-1]
    if int(np.sum(size[fa] + size[fb])) > MAX_PAIRS:
        return None

    def reach(f, g):
        """(pair index, triangle) of the triangles of faces f (K,) meeting g's box."""
        k = np.repeat(np.arange(len(f)), size[f])
        t = order[ranges(start[f], size[f])]
        ok = (tlo[t] <= fhi[g[k]]).all(axis=1) & (flo[g[k]] <= thi[t]).all(axis=1)
        return k[ok], t[ok]

    ka, ta = reach(fa, fb)
    kb, tb = reach(fb, fa)
    na = np.bincount(ka, minlength=len(fa))
    nb = np.bincount(kb, minlength=len(fa))
    total = int(np.sum(na * nb))
    if total > MAX_PAIRS:
        return None
    sa = np.cumsum(na) - na
    sb = np.cumsum(nb) - nb
    k = np.repeat(np.arange(len(fa)), na * nb)
    r = ranges(np.zeros(len(fa), np.int64), na * nb)      # the pair's own 0 .. na nb - 1
    A = ta[sa[k] + r // np.maximum(nb[k], 1)]
    B = tb[sb[k] + r % np.maximum(nb[k], 1)]
    pairs = crossing_pairs(X, T, np.stack([A, B], axis=1))
    if pairs is None or not len(pairs):
        return pairs
    # where the cage itself crosses near both faces, so does the surface, as drawn: the cage's
    # faces near the crossing ones (sharing a position), fanned, checked against each other
    def near(mask):
        return np.asarray(inc.T @ (inc @ mask.astype(np.int32)) > 0).ravel()

    involved = np.zeros(F, bool)
    involved[tf[pairs.ravel()]] = True
    zone = near(involved)
    ct, cown = _fan(topology, np.flatnonzero(zone))
    own = crossing_pairs(np.asarray(cage, dtype=np.float64), ct)
    if own is None:
        return None
    hit = np.zeros(F, bool)
    if len(own):
        hit[np.unique(cown[own.ravel()])] = True
    # and where the cage's fans touch at a point (a bow-tie the repair split, an open seam:
    # positions of several vertices), their surfaces meet near it as drawn (a Suzanne
    # exported as STL and joined by position crossed at her two bow-ties)
    copies = np.bincount(pid[np.unique(np.asarray(topology.face_vertices))],
                         minlength=inc.shape[0])
    touch = np.asarray(inc.T @ (copies > 1).astype(np.int32) > 0).ravel()
    hit = near(hit | touch)
    return pairs[~(hit[tf[pairs[:, 0]]] & hit[tf[pairs[:, 1]]])]


def self_crossing_warning(pairs, triangle_faces) -> MeshWarning | None:
    """A ``self_crossing`` :class:`gerbs_core.mesh.repair.MeshWarning` naming the input faces
    (``triangle_faces`` (T,): each lattice triangle's input face) that hold crossing
    triangles, or None where no pair crosses."""
    if pairs is None or not len(pairs):
        return None
    faces = np.unique(np.asarray(triangle_faces)[np.asarray(pairs).ravel()])
    return MeshWarning(
        "self_crossing",
        f"the surface passes through itself ({len(pairs)} pairs of its triangles at the "
        f"check's resolution cross) where the mesh does not: where the two sides of a thin "
        f"part are close in space but far apart in the mesh (a mug's wall or floor, a table "
        f"top), or where it folds sharply, the local functions bulge into each other; more "
        f"loop cuts there (across a thin part as many on each side), or a bevel, keep them "
        f"apart; faces",
        tuple(int(f) for f in faces), "face")
