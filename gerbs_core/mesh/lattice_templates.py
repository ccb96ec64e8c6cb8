"""Lattice templates: the sample points of one n-gon at resolution r (:mod:`.lattice`).

Every face with n corners is sampled by the same template (cached per (n, r)):
triangles by the barycentric lattice {(i, j) / r}, quads by the r x r bilinear
lattice, n-gons (n >= 5) by a fan of n barycentric lattices from the face centre.
Each template point carries its parameters in the face and its kind: a corner, a
point inside a side (corner k -> k+1) at position m = 1..r-1 from corner k, or an
interior point. :class:`~gerbs_core.mesh.lattice.Lattice` maps these to the global
samples, so points on shared vertices and edges are stored once.

Obtuse triangles get another triangulation of the same points (a *variant* k = the
obtuse corner, -1 the standard one; :func:`flipped_triangles`): every lattice triangle
is similar to its face, so a face with a 164-degree corner would give r^2 slivers, and
the corner triangle at the obtuse vertex spans ~180 degrees of that vertex's chart (its
image is degenerate whatever the surface; docs/design.md, stage 9).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["CORNER", "EDGE", "INTERIOR", "FLIP_ANGLE", "face_counts", "template",
           "template_faces", "template_edges", "template_tris", "flipped_triangles",
           "obtuse_flips", "variant_rows"]

CORNER, EDGE, INTERIOR = 0, 1, 2

# triangles with a layout corner above this (degrees) are triangulated by
# flipped_triangles (docs/design.md, stage 9: measured 110 / 120 / 135)
FLIP_ANGLE = 120.0


def face_counts(sizes: np.ndarray, r: int):
    """(interior samples, output triangles) per face of the given corner counts."""
    sizes = np.asarray(sizes, dtype=np.int64)
    nt = (r - 1) * (r - 2) // 2
    inner = np.where(sizes == 3, nt, np.where(sizes == 4, (r - 1) ** 2,
                                              1 + sizes * (r - 1) + sizes * nt))
    tris = np.where(sizes == 4, 2 * r * r, np.where(sizes == 3, r * r, sizes * r * r))
    return inner, tris


def _barycentric(r: int):
    """The barycentric lattice {(i, j): i + j <= r}, j-major.

    Returns (i, j, tris, inner, inum): the point coordinates (m,), the counter-clockwise
    lattice triangles (r^2, 3) (the up triangles (i,j),(i+1,j),(i,j+1) first, then the
    down ones), the interior mask (m,) and each interior point's number among them.
    """
    ij = np.array([(i, j) for j in range(r + 1) for i in range(r + 1 - j)], dtype=np.int64)
    i, j = ij[:, 0], ij[:, 1]
    lut = np.full((r + 1, r + 1), -1, dtype=np.int64)
    lut[i, j] = np.arange(len(ij))
    up = ij[i + j < r]
    dn = ij[i + j < r - 1]
    tris = np.concatenate([
        np.stack([lut[up[:, 0], up[:, 1]], lut[up[:, 0] + 1, up[:, 1]], lut[up[:, 0], up[:, 1] + 1]], 1),
        np.stack([lut[dn[:, 0] + 1, dn[:, 1]], lut[dn[:, 0] + 1, dn[:, 1] + 1],
                  lut[dn[:, 0], dn[:, 1] + 1]], 1)])
    inner = (i >= 1) & (j >= 1) & (i + j < r)
    return i, j, tris, inner, np.cumsum(inner) - 1


def _mark(kind, loc, pos, i, j, r, corners, sides):
    """Set the corners ((ci, cj), k) and the side points (mask, k, position) in place."""
    for (ci, cj), k in corners:
        sel = (i == ci) & (j == cj)
        kind[sel], loc[sel] = CORNER, k
    for sel, k, m in sides:
        kind[sel], loc[sel], pos[sel] = EDGE, k, m[sel]


def _triangle(r: int):
    """Template of a triangle: uv = (l1, l2), the barycentric weights of corners 1, 2."""
    i, j, tris, _, inum = _barycentric(r)
    m_ = len(i)
    kind = np.full(m_, INTERIOR)
    loc, pos = inum.copy(), np.zeros(m_, dtype=np.int64)
    _mark(kind, loc, pos, i, j, r, (((0, 0), 0), ((r, 0), 1), ((0, r), 2)),
          (((j == 0) & (i > 0) & (i < r), 0, i),
           ((i + j == r) & (j > 0) & (j < r), 1, j),
           ((i == 0) & (j > 0) & (j < r), 2, r - j)))
    uv = np.stack([i, j], 1) / r
    return uv, np.full(m_, -1), kind, loc, pos, np.ones(m_, dtype=bool), tris


def _quad(r: int):
    """Template of a quad: uv = (s, t) bilinear, i-fastest; two triangles per cell."""
    jj, ii = np.meshgrid(np.arange(r + 1), np.arange(r + 1), indexing="ij")
    i, j = ii.ravel(), jj.ravel()
    m_ = len(i)
    kind = np.full(m_, INTERIOR)
    loc = (j - 1) * (r - 1) + (i - 1)
    pos = np.zeros(m_, dtype=np.int64)

    def mid(a):
        return (a > 0) & (a < r)
    _mark(kind, loc, pos, i, j, r, (((0, 0), 0), ((r, 0), 1), ((r, r), 2), ((0, r), 3)),
          (((j == 0) & mid(i), 0, i), ((i == r) & mid(j), 1, j),
           ((j == r) & mid(i), 2, r - i), ((i == 0) & mid(j), 3, r - j)))
    cj, ci = np.meshgrid(np.arange(r), np.arange(r), indexing="ij")
    a = (cj * (r + 1) + ci).ravel()
    b, c, d = a + 1, a + r + 2, a + r + 1
    tris = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    uv = np.stack([i, j], 1) / r
    return uv, np.full(m_, -1), kind, loc, pos, np.ones(m_, dtype=bool), tris


def _fan(n: int, r: int):
    """Template of an n-gon: fan k has (l1, l2) = (i, j)/r, the weights of corners k and
    k+1 (the centre's the rest). Interior numbers: 0 the centre, then the spokes' r-1
    points each, then the fans' interiors. A point repeated in two fans (the centre,
    corner k+1, spoke k+1) is canonical only in one of them."""
    i0, j0, tri_t, inner_t, inum_t = _barycentric(r)
    m_ = len(i0)
    nt = (r - 1) * (r - 2) // 2
    k_ = np.repeat(np.arange(n), m_)
    i, j = np.tile(i0, n), np.tile(j0, n)
    kind = np.full(n * m_, INTERIOR)
    loc = np.zeros(n * m_, dtype=np.int64)
    pos = np.zeros(n * m_, dtype=np.int64)
    canon = np.ones(n * m_, dtype=bool)
    canon[(i == 0) & (j == 0) & (k_ > 0)] = False
    sel = (i == r) & (j == 0)
    kind[sel], loc[sel] = CORNER, k_[sel]
    sel = (i == 0) & (j == r)
    kind[sel], loc[sel], canon[sel] = CORNER, (k_[sel] + 1) % n, False
    sel = (i + j == r) & (j > 0) & (j < r)
    kind[sel], loc[sel], pos[sel] = EDGE, k_[sel], j[sel]
    sel = (j == 0) & (i > 0) & (i < r)  # spoke k
    loc[sel] = 1 + k_[sel] * (r - 1) + i[sel] - 1
    sel = (i == 0) & (j > 0) & (j < r)  # spoke k+1, owned by fan k+1
    loc[sel], canon[sel] = 1 + ((k_[sel] + 1) % n) * (r - 1) + j[sel] - 1, False
    sel = np.tile(inner_t, n)
    loc[sel] = 1 + n * (r - 1) + k_[sel] * nt + np.tile(inum_t, n)[sel]
    tris = (tri_t[None] + (np.arange(n) * m_)[:, None, None]).reshape(-1, 3)
    return np.stack([i, j], 1) / r, k_, kind, loc, pos, canon, tris


@lru_cache(maxsize=64)
def template(n: int, r: int):
    """Lattice template of an n-gon at resolution r (read-only arrays).

    Returns (uv, fan, kind, loc, pos, canonical, tris): per lattice point its
    parameters and fan, its kind (corner/edge/interior), ``loc`` the corner or
    edge (k: corner k -> k+1) number or the interior number, ``pos`` = m, the
    position 1..r-1 along edge ``loc`` from corner k; ``canonical`` marks the
    one occurrence of each point of the face that may own it; ``tris`` the
    counter-clockwise lattice triangles in template indices.
    """
    parts = _triangle(r) if n == 3 else _quad(r) if n == 4 else _fan(n, r)
    uv, fan, kind, loc, pos, canon, tris = parts
    out = (uv.astype(np.float64), fan.astype(np.int64), kind.astype(np.int64),
           loc.astype(np.int64), pos.astype(np.int64), canon, tris.astype(np.int64))
    for a in out:
        a.flags.writeable = False
    return out


def flipped_triangles(r: int, k: int) -> np.ndarray:
    """The barycentric lattice of :func:`template` (3, r) triangulated for an obtuse corner
    k: (r^2, 3) counter-clockwise triangles in template indices.

    Every down triangle is paired with the up triangle across its edge parallel to the
    side opposite corner k, and the parallelogram is split along its other diagonal (the
    one pointing at corner k); the r up triangles along that side stay. Written for
    k = 0 in coordinates (a, b) = (l_{k+1}, l_{k+2}) r (a cyclic relabelling of the
    corners, which keeps the orientation): cell (a, b) gives (a, b), (a+1, b), (a+1, b+1)
    and (a, b), (a+1, b+1), (a, b+1). The corner triangle (k, p, q) becomes (k, p, c),
    (k, c, q) with c = p + q - k, on the bisector: at (164, 8, 8) degrees the new
    triangles have angles about (16, 82, 82) instead of the face's."""
    i, j = _barycentric(r)[:2]
    lut = np.full((r + 1, r + 1), -1, dtype=np.int64)
    lut[i, j] = np.arange(len(i))
    ab = np.array([(a, b) for b in range(r) for a in range(r - b)], dtype=np.int64)
    a, b = ab[:, 0], ab[:, 1]
    c = a + b < r - 1  # the cells; the others are the up triangles along the side

    def tri(*pts):
        return np.stack([np.stack(p, -1) for p in pts], 1)  # (t, 3 corners, (a, b))
    tris = np.concatenate([tri((a, b), (a + 1, b), (a + c, b + 1)),  # cell or up triangle
                           tri((a[c], b[c]), (a[c] + 1, b[c] + 1), (a[c], b[c] + 1))])
    l_rot = np.concatenate([(r - tris.sum(-1))[..., None], tris], -1)  # (l_k, l_k+1, l_k+2)
    l = np.roll(l_rot, k, axis=-1)  # l[..., m] = l_rot[..., (m - k) % 3]
    return lut[l[..., 1], l[..., 2]]


@lru_cache(maxsize=64)
def template_tris(n: int, r: int, variant: int = -1) -> np.ndarray:
    """The template's triangles (read-only (r^2 n', 3)): ``template(n, r)`` 's for variant
    -1, :func:`flipped_triangles` (r, variant) for a triangle's variant 0..2."""
    if variant < 0:
        return template(n, r)[6]
    if n != 3 or variant > 2:
        raise ValueError(f"variant {variant} of an {n}-gon: only triangles have 0..2")
    out = flipped_triangles(r, variant)
    out.flags.writeable = False
    return out


def obtuse_flips(topology, angles, threshold: float | None = None) -> np.ndarray:
    """(F,) int64 variant of every face: its largest corner k (0..2) for triangles whose
    layout angle there (``angles`` (C,) radians, :class:`~.layout.FaceLayouts`) exceeds
    ``threshold`` degrees (default :data:`FLIP_ANGLE`), else -1."""
    t = np.deg2rad(FLIP_ANGLE if threshold is None else threshold)
    sizes = np.asarray(topology.face_sizes)
    out = np.full(len(sizes), -1, dtype=np.int64)
    tri = np.flatnonzero(sizes == 3)
    if len(tri):
        a = np.asarray(angles)[topology.face_offsets[tri][:, None] + np.arange(3)]
        k = np.argmax(a, axis=1)
        big = a[np.arange(len(tri)), k] > t
        out[tri[big]] = k[big]
    return out


def variant_rows(variants: np.ndarray):
    """[(rows, variant)] of a size class's faces (``variants`` (nf,)), to be written in
    order: all of them (a slice) as variant -1 first, then the index arrays of each other
    variant present, overwriting theirs (few faces are flipped: the bulk stays one block)."""
    v = np.asarray(variants)
    return [(slice(None), -1)] + [(np.flatnonzero(v == u), int(u))
                                  for u in np.unique(v[v >= 0]).tolist()]


@lru_cache(maxsize=64)
def template_faces(n: int, r: int, quads: bool = False, variant: int = -1) -> np.ndarray:
    """Output faces of an n-gon template in template indices (read-only (k, m) array):
    with `quads` a quad's r x r cells (m = 4; cell (i, j) -> (i+1, j) -> (i+1, j+1) ->
    (i, j+1), counter-clockwise like the face), else the lattice triangles (m = 3) of
    the `variant` (:func:`template_tris`)."""
    tris = template_tris(n, r, variant)
    if not (quads and n == 4):
        return tris
    c = r * r  # the triangles of a quad are (a, b, c) for every cell, then (a, c, d)
    out = np.stack([tris[:c, 0], tris[:c, 1], tris[:c, 2], tris[c:, 2]], 1)
    out.flags.writeable = False
    return out


def _side_segments(tedge, kind, loc, pos, n: int, r: int):
    """(side, seg) of template edges (te, 2): side k and segment m (from position m to
    m+1 counted from corner k) for edges along the polygon's side k, side -1 inside."""
    npt = len(kind)
    side = np.full(len(tedge), -1, dtype=np.int64)
    seg = np.zeros(len(tedge), dtype=np.int64)
    for k in range(n):
        sp = np.full(npt, -1, dtype=np.int64)  # position along side k, or -1
        sp[(kind == CORNER) & (loc == k)] = 0
        sp[(kind == CORNER) & (loc == (k + 1) % n)] = r
        on = (kind == EDGE) & (loc == k)
        sp[on] = pos[on]
        pa, pb = sp[tedge[:, 0]], sp[tedge[:, 1]]
        on = (pa >= 0) & (pb >= 0) & (np.abs(pa - pb) == 1)
        side[on], seg[on] = k, np.minimum(pa, pb)[on]
    return side, seg


@lru_cache(maxsize=64)
def template_edges(n: int, r: int, quads: bool = False, variant: int = -1):
    """Edges of the output faces of an n-gon template (:func:`template_faces`; read-only).

    Returns (tedge (te, 2), face_edge (k, m), side (te,), seg (te,)): the distinct
    undirected edges in template indices (repeated template points, e.g. an n-gon's
    centre, merged), the edge from corner i to corner i+1 of every template
    face, and for edges along the polygon's side k (corner k -> k+1) side = k
    and seg = m, the segment from position m to m+1 counted from corner k; side =
    -1 for edges inside the polygon (these come first).
    """
    uv, fan, kind, loc, pos, canon, _ = template(n, r)
    tris = template_faces(n, r, quads, variant)
    npt = len(kind)
    _, first, inv = np.unique(np.stack([kind, loc, pos], 1), axis=0, return_index=True,
                              return_inverse=True)
    cid = first[inv.ravel()]  # canonical template index of every occurrence
    a = cid[tris]
    b = cid[np.roll(tris, -1, axis=1)]
    ukey, tri_edge = np.unique(np.minimum(a, b) * npt + np.maximum(a, b), return_inverse=True)
    tedge = np.stack([ukey // npt, ukey % npt], 1)
    side, seg = _side_segments(tedge, kind, loc, pos, n, r)
    order = np.argsort(side >= 0, kind="stable")  # inner edges first
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    out = (tedge[order], rank[tri_edge].reshape(tris.shape), side[order], seg[order])
    for x in out:
        x.flags.writeable = False
    return out
