"""Star-shaped covers of scattered points in the plane (paper sections 4-5, DESIGN
section 4): the constructors of :class:`~gerbs_core.scattered.planar_star.PlanarStarCover`
(the batched smooth star gauge, its own module).

Cover constructors:

* :func:`delaunay_cover` - star-1 neighbourhoods of the Delaunay vertices
  (Example 8); hull vertices have open stars (sectors). Domain: the convex hull.
* :func:`voronoi_cover` - the Voronoi cell V_i of each site, clipped to a convex
  domain polygon, enlarged about its site by 2 (x_i + 2 (V_i - x_i)). The factor 2
  is the largest for which no other site enters the interior (every bisector is
  pushed exactly onto the neighbour), so the cover is minimally supported
  (section 4.4) and thick (it contains every closed cell in its interior). This
  is our reading of "star-1 neighbourhoods in a Voronoi diagram" for covers
  centred at the data sites (the paper's Example 9 centres them at Voronoi
  vertices, which carry no data).
* :func:`polygon_cover` - user polygons, each star-shaped w.r.t. its point.
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, InvalidPointSetError
from .planar_star import PlanarStarCover, cross2d, signed_angle
from .triangulation import delaunay

__all__ = ["PlanarStarCover", "delaunay_cover", "voronoi_cover", "polygon_cover", "padded_ball_query"]


def padded_ball_query(tree, x, r, p=2.0, k0=16):
    """Indices of all tree points within distance r of each x, as a padded (M, K)
    int array (-1 = empty slot), via k-NN queries (vectorized), doubling K for rows
    that come back full. Rows of x with a NaN or infinite coordinate have no points (the
    KD-tree refuses them; the evaluation then gives them its fill value)."""
    finite = np.isfinite(x).all(axis=1)
    if not finite.all():
        out = np.full((x.shape[0], 1), -1, dtype=np.int64)
        if finite.any():
            inner = padded_ball_query(tree, x[finite], r, p, k0)
            out = np.full((x.shape[0], inner.shape[1]), -1, dtype=inner.dtype)
            out[finite] = inner
        return out
    M = x.shape[0]
    n_tree = tree.n
    k = min(k0, n_tree)
    d, idx = tree.query(x, k=k, distance_upper_bound=r, p=p)
    d = d.reshape(M, k)
    idx = idx.reshape(M, k)
    full = np.isfinite(d[:, -1])
    while full.any() and k < n_tree:
        k = min(2 * k, n_tree)
        rows = np.flatnonzero(full)
        d2, i2 = tree.query(x[rows], k=k, distance_upper_bound=r, p=p)
        d2, i2 = d2.reshape(len(rows), k), i2.reshape(len(rows), k)
        idx = np.concatenate([idx, np.full((M, k - idx.shape[1]), n_tree)], axis=1)
        idx[rows] = i2
        full = np.zeros(M, bool)
        full[rows] = np.isfinite(d2[:, -1])
    idx = np.where(idx >= n_tree, -1, idx)
    used = np.flatnonzero((idx >= 0).any(axis=0))
    return idx[:, : (used.max() + 1 if used.size else 1)]


def delaunay_triangulation(points):
    """The Delaunay triangulation (a :class:`~gerbs_core.scattered.triangulation.Triangulation`,
    Qhull on normalised coordinates) and its simplices (T, 3) and neighbours (T, 3), made
    counter-clockwise; raise InvalidPointSetError for degenerate sets."""
    if points.shape[1] != 2:
        raise InvalidParameterError("cover", "star covers are planar: points must have n = 2")
    if points.shape[0] < 3:
        raise InvalidPointSetError(f"points: a Delaunay cover needs >= 3 points, got {points.shape[0]}")
    tri = delaunay(points)
    _set_transforms(tri.qhull, tri.qhull.points)     # (find_simplex's, normalised)
    tri.transform          # (the caller's coordinates too, from them: the same bits near 0)
    s = tri.simplices.copy()
    nb = tri.neighbors.copy()
    P = points[s]
    area = cross2d(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    neg = area < 0
    s[neg, 1], s[neg, 2] = s[neg, 2].copy(), s[neg, 1].copy()
    nb[neg, 1], nb[neg, 2] = nb[neg, 2].copy(), nb[neg, 1].copy()    # neighbour j is opposite vertex j
    return tri, s, nb


def _set_transforms(tri, points):
    """Fill ``tri``'s barycentric transforms (nsimplex, 3, 2) in one vectorized pass.

    scipy computes them lazily on the first ``find_simplex``, one LAPACK LU per
    triangle: 0.2 s for 10^5 points, a fifth of a CloughTocher2DInterpolator fit.
    Same layout and rule: rows 0-1 the inverse of T = [p0 - p2, p1 - p2] (columns),
    row 2 the vertex p2; NaN where the 1-norm reciprocal condition number of T is
    below 1000 eps (degenerate triangles, scipy's limit). Differs from LAPACK's only in rounding."""
    s = tri.simplices
    r = points[s[:, 2]]
    d0, d1 = points[s[:, 0]] - r, points[s[:, 1]] - r            # T = [[a, b], [c, d]]
    a, c, b, d = d0[:, 0], d0[:, 1], d1[:, 0], d1[:, 1]
    out = np.empty((len(s), 3, 2))
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_det = 1.0 / (a * d - b * c)
        np.multiply(d, inv_det, out=out[:, 0, 0])
        np.multiply(-b, inv_det, out=out[:, 0, 1])
        np.multiply(-c, inv_det, out=out[:, 1, 0])
        np.multiply(a, inv_det, out=out[:, 1, 1])
        norm_t = np.maximum(np.abs(a) + np.abs(c), np.abs(b) + np.abs(d))
        A = np.abs(out[:, :2])
        norm_i = np.maximum(A[:, 0, 0] + A[:, 1, 0], A[:, 0, 1] + A[:, 1, 1])
        # scipy's rule (_get_barycentric_transforms: rcond_limit = 1000 eps): a sliver
        # stored finite would stop find_simplex's walk where scipy's widens its search
        bad = ~(1.0 / (norm_t * norm_i) >= 1000 * np.finfo(float).eps)
    out[:, 2] = r
    out[bad] = np.nan
    # scipy's cache of the property ``transform`` (a private attribute, None until the
    # first find_simplex; tests/core/test_covers.py compares with scipy's own): filled
    # only where this scipy has it empty, else scipy builds it as before
    if getattr(tri, "_transform", 0) is None:
        tri._transform = out


def _corner_in(s, tri_idx, vertex):
    """Edge index 3 t + k of the corner of triangle ``tri_idx`` at ``vertex`` (-1 if none).

    From two gathers of the flat simplices (not an (E, 3) one) and in place: the same
    integers (k = 0 if ``vertex`` is neither of the other corners, as argmax)."""
    sf = s.reshape(-1)
    t3 = np.maximum(tri_idx, 0)
    t3 *= 3
    k = np.equal(sf.take(t3 + 1), vertex)
    out = t3 + k
    np.equal(sf.take(t3 + 2), vertex, out=k)
    out += 2 * k
    out[tri_idx < 0] = -1
    return out


def delaunay_cover(points, kernel, **gauge_kw):
    """Star-1 neighbourhoods of the Delaunay vertices. Returns (cover, tri, simplices)
    with the edge of corner k of triangle t at index 3 t + k."""
    tri, s, nb = delaunay_triangulation(points)
    star = s.reshape(-1)
    i0 = s[:, [1, 2, 0]].reshape(-1)
    i1 = s[:, [2, 0, 1]].reshape(-1)
    # corner (t, k): the next edge of star a = s[t, k] is in the triangle across
    # the edge (a, i1), i.e. opposite vertex i0 = s[t, k+1]; prev: opposite i1
    nxt = _corner_in(s, nb[:, [1, 2, 0]].reshape(-1), star)
    prv = _corner_in(s, nb[:, [2, 0, 1]].reshape(-1), star)
    # the edges' end points gathered coordinate-major: (E, 2) views with contiguous columns
    pts_t = np.ascontiguousarray(points.T)
    q0, q1 = pts_t.take(i0, axis=1).T, pts_t.take(i1, axis=1).T
    # in a triangle some vertex has barycentric coordinate >= 1/3: exact gauge <= 2/3
    cover = PlanarStarCover(points, star, q0, q1, nxt, prv, kernel, domain_gauge=2.0 / 3.0,
                            **gauge_kw)
    return cover, tri, s


def _rings_cover(centers, rings, kernel, **gauge_kw):
    """Closed star polygons (list of (K_i, 2) CCW rings) -> PlanarStarCover."""
    stars, q0, q1, i0, i1 = [], [], [], [], []
    off = 0
    bad = []
    for i, ring in enumerate(rings):
        ring = np.asarray(ring, float)
        if ring.ndim != 2 or ring.shape[1] != 2 or len(ring) < 3 or not np.all(np.isfinite(ring)):
            bad.append(i)
            continue
        K = len(ring)
        stars.append(np.full(K, i))
        q0.append(ring)
        q1.append(np.roll(ring, -1, axis=0))
        i0.append(off + np.arange(K))
        i1.append(off + np.roll(np.arange(K), -1))
        off += K
    if bad:
        raise InvalidPointSetError("cover polygons need >= 3 finite vertices, shape (K, 2); bad polygons", bad)
    star = np.concatenate(stars)
    q0, q1 = np.concatenate(q0), np.concatenate(q1)
    c = centers[star]
    tot = np.zeros(len(centers))
    np.add.at(tot, star, signed_angle(q0 - c, q1 - c))
    notstar = np.flatnonzero(np.abs(tot - 2 * np.pi) > 1e-8)
    if notstar.size:
        raise InvalidPointSetError(
            "cover polygons must be counter-clockwise and star-shaped w.r.t. (and contain) their "
            "point; offending points", notstar)
    i0, i1 = np.concatenate(i0), np.concatenate(i1)
    nxt = np.empty(len(star), int)
    prv = np.empty(len(star), int)
    nxt[:] = np.arange(len(star)) + 1
    prv[:] = np.arange(len(star)) - 1
    starts = np.concatenate([[0], np.cumsum([len(s) for s in stars])])
    for a, b in zip(starts[:-1], starts[1:]):
        nxt[b - 1] = a
        prv[a] = b - 1
    return PlanarStarCover(centers, star, q0, q1, nxt, prv, kernel, **gauge_kw)


def polygon_cover(points, polygons, kernel, **gauge_kw):
    """User cover polygons: ``polygons[i]`` (K_i, 2), CCW, star-shaped w.r.t. points[i]."""
    if len(polygons) != points.shape[0]:
        raise InvalidParameterError("cover", f"need one polygon per point ({points.shape[0]}), got {len(polygons)}")
    return _rings_cover(points, polygons, kernel, **gauge_kw)


def _clip(poly, a, b):
    """Clip a convex CCW polygon (K, 2) by the half-plane a . x <= b."""
    s = poly @ a - b
    out = []
    K = len(poly)
    for k in range(K):
        P, Q = poly[k], poly[(k + 1) % K]
        sp, sq = s[k], s[(k + 1) % K]
        if sp <= 0:
            out.append(P)
        if (sp < 0 < sq) or (sq < 0 < sp):
            out.append(P + (Q - P) * (sp / (sp - sq)))
    return np.array(out) if out else np.zeros((0, 2))


def voronoi_cells(points, domain):
    """Voronoi cells clipped to the convex CCW polygon ``domain`` (list of (K_i, 2))."""
    tri, s, _ = delaunay_triangulation(points)
    indptr, nbrs = tri.vertex_neighbor_vertices
    cells = []
    for i in range(points.shape[0]):
        cell = domain
        for j in nbrs[indptr[i]:indptr[i + 1]]:
            a = points[j] - points[i]
            b = a @ (0.5 * (points[i] + points[j]))
            cell = _clip(cell, a, b)
        # drop (near-)repeated vertices created by clipping
        # (relative to the coordinates' size: points of any scale, module triangulation)
        keep = np.linalg.norm(cell - np.roll(cell, 1, axis=0), axis=1) > 1e-12 * np.abs(cell).max()
        cells.append(cell[keep])
    return cells


def _as_domain(domain, points):
    if domain is None:
        lo, hi = points.min(0), points.max(0)
        pad = 0.05 * (hi - lo).max()
        lo, hi = lo - pad, hi + pad
        domain = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    domain = np.asarray(domain, float)
    if domain.ndim != 2 or domain.shape[1] != 2 or len(domain) < 3:
        raise InvalidParameterError("domain", "need a convex polygon (K, 2), counter-clockwise")
    e = np.roll(domain, -1, 0) - domain
    if np.any(cross2d(e, np.roll(e, -1, 0)) <= 0):
        raise InvalidParameterError("domain", "polygon must be convex and counter-clockwise")
    # points strictly inside
    rel = points[:, None, :] - domain[None]
    out = np.flatnonzero(np.any(cross2d(e[None], rel) <= 0, axis=1))
    if out.size:
        raise InvalidPointSetError("points: outside (or on the boundary of) the domain polygon at indices", out)
    return domain


def voronoi_cover(points, kernel, domain=None, scale=2.0, **gauge_kw):
    """Doubled clipped Voronoi cells (see module doc). Returns (cover, domain)."""
    if not (1.0 < scale <= 2.0):
        raise InvalidParameterError("scale", f"need 1 < scale <= 2 (2 = minimal support limit), got {scale}")
    domain = _as_domain(domain, points)
    cells = voronoi_cells(points, domain)
    rings = [points[i] + scale * (c - points[i]) for i, c in enumerate(cells)]
    # a domain point lies in its own cell: exact gauge of the enlarged cell <= 1 / scale
    return _rings_cover(points, rings, kernel, domain_gauge=1.0 / scale, **gauge_kw), domain


def in_convex_polygon(x, poly):
    e = np.roll(poly, -1, 0) - poly
    rel = x[:, None, :] - poly[None]
    return np.all(cross2d(e[None], rel) >= 0, axis=1)
