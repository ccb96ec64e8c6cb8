"""Covers: balls of a metric (general construction) and star-shaped covers in the
plane (paper sections 4-5, DESIGN section 4).

Planar star covers are held by :class:`PlanarStarCover`, a *batched* smooth star
gauge: all N elements at once in flat arrays, because one Python object per
element (``gauge.StarGauge``) would cost ~N Python calls for N = 10^5..10^6.
It follows the gauge rule of DESIGN section 4 (same as ``gauge.StarGauge``):

* the exact radius of the polygon about its centre is piecewise
  rho(t) = p_e / cos(t - nu_e) on each boundary edge e, t the angle from the
  direction to the edge's first corner;
* u~ = 1/rho~ is a GERBS spline in the angle whose local functions are the edges'
  own lines u_e = cos(t - nu_e)/p_e, pulled in by c_e in [kappa, 1] (0.9-0.97
  next to convex corners, as close to 1 as lets their transitions fill the room:
  :func:`gerbs_core.gauge.blend.adaptive_scales`; 1 between reflex ones),
  with ONE transition per
  corner, as wide as certified (up to half of each adjacent edge, see
  ``_subdivide`` and :func:`gerbs_core.gauge.blend.blend_check`), so
  kappa rho <= rho~ <= rho; then rho~ is scaled by ``shrink`` = 0.95. (The
  earlier rule -- constants at knots in the log-radius variable -- made rho~ a
  staircase whose derivatives jumped by O(1) within 1e-4 on the unit square.)
* Thickness of the Delaunay cover is guaranteed: in a triangle the exact gauge of
  vertex a is 1 - lambda_a (barycentric), max lambda >= 1/3, and
  rho~ >= kappa shrink rho = 0.76 rho > 2/3 rho, so some psi_a >= b(0.667/0.76) > 0.
* g(x) = |x - c| / rho~(theta), psi = b(g). With a kernel flat at 0 and 1 (ERBS)
  rho~ and psi are C-infinity; supp psi lies strictly inside the polygon.
* ``exact=True`` uses shrink * rho (the kinked polygon radius): psi then has
  kinks along the corner rays (used by the tests to show the checks bite).

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
from scipy.spatial import Delaunay, QhullError

from ..errors import InvalidParameterError, InvalidPointSetError
from ..gauge.jet import bump_jet, polar_jet, star_gauge_jet

__all__ = ["PlanarStarCover", "delaunay_cover", "voronoi_cover", "polygon_cover", "padded_ball_query"]


def padded_ball_query(tree, x, r, p=2.0, k0=16):
    """Indices of all tree points within distance r of each x, as a padded (M, K)
    int array (-1 = empty slot), via k-NN queries (vectorized), doubling K for rows
    that come back full."""
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


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _angle(a, b):
    """Signed angle from a to b in (-pi, pi]."""
    return np.arctan2(_cross(a, b), np.sum(a * b, axis=-1))


class PlanarStarCover:
    """N planar star-shaped polygons (closed or open fans), with smooth gauges.

    Parameters
    ----------
    centers : (N, 2) the star centres x_i.
    edge_star : (E,) int, the star of each boundary edge.
    q0, q1 : (E, 2) edge end points, counter-clockwise as seen from the centre.
    next_edge, prev_edge : (E,) int, neighbouring edge of the same star (-1 at the
        ends of an open star).
    kernel : the GERBS kernel (b and the envelope spline).
    """

    def __init__(self, centers, edge_star, q0, q1, next_edge, prev_edge, kernel,
                 kappa=0.8, shrink=0.95, exact=False):
        if not (0 < kappa < 1):
            raise InvalidParameterError("kappa", f"need 0 < kappa < 1, got {kappa}")
        if not (0 < shrink <= 1):
            raise InvalidParameterError("shrink", f"need 0 < shrink <= 1, got {shrink}")
        self.centers = centers
        self.kernel = kernel
        self.kappa, self.shrink, self.exact = float(kappa), float(shrink), bool(exact)
        self.edge_star = np.asarray(edge_star)
        self.next_edge = np.asarray(next_edge)
        self.prev_edge = np.asarray(prev_edge)
        c = centers[self.edge_star]
        a0, a1 = q0 - c, q1 - c
        self.a0, self.a1 = a0, a1
        self._corner_r = np.maximum(np.linalg.norm(a0, axis=1), np.linalg.norm(a1, axis=1))
        self.delta = _angle(a0, a1)
        bad = np.flatnonzero(~(self.delta > 1e-12) | ~(self.delta < np.pi - 1e-12))
        if bad.size:
            raise InvalidPointSetError(
                "cover polygons are not star-shaped w.r.t. their points (edge seen under an angle "
                "outside (0, pi)); offending points", np.unique(self.edge_star[bad]))
        e = q1 - q0
        self.p = _cross(a0, a1) / np.linalg.norm(e, axis=-1)
        t = -np.sum(a0 * e, -1) / np.sum(e * e, -1)
        foot = a0 + t[:, None] * e
        self.nu = _angle(a0, foot)
        self._subdivide()

    # -- the envelope -----------------------------------------------------
    def _subdivide(self):
        """Corner transitions of the envelope (DESIGN section 4, same rule as
        :func:`gerbs_core.gauge.blend.build_blend`).

        u~ = 1/rho~ is a GERBS spline in the angle whose local functions are the
        edges' own lines u_e = cos(t - nu_e) / p_e pulled in by c_e (kappa <= c_e
        <= 1, from the edge's two corners: ``adaptive_scales``), blended across each
        corner over [delta_e - R_e, delta_e] of edge e and [0, L_f] of the next
        edge f: one transition per corner, initially half of each edge (the
        whole edge at an open end), narrowed until
        :func:`~gerbs_core.gauge.blend.blend_check` certifies
        kappa rho <= rho~/shrink <= rho on it (rigorous bound, not sampling).
        """
        from ..gauge.blend import adaptive_scales, fit_blend_widths
        E = len(self.delta)
        e = np.flatnonzero(self.next_edge >= 0)
        f = self.next_edge[e]
        nA, nB = self.nu[e] - self.delta[e], self.nu[f]
        roomA = self.delta[e] * np.where(self.prev_edge[e] >= 0, 0.5, 1.0)
        roomB = self.delta[f] * np.where(self.next_edge[f] >= 0, 0.5, 1.0)
        self.c = adaptive_scales(E, e, f, nA, self.p[e], nB, self.p[f], roomA, roomB,
                                 self.kappa, self.kernel)
        wa, wb, ok, _, _ = fit_blend_widths(nA, self.p[e], self.c[e], nB, self.p[f], self.c[f],
                                            roomA, roomB, self.kappa, self.kernel)
        if not ok.all():
            raise InvalidPointSetError(
                "no certified smooth gauge at a corner of these stars (degenerate polygon); "
                "offending points", np.unique(self.edge_star[e[~ok]]))
        self.R, self.L = np.zeros(E), np.zeros(E)
        self.R[e], self.L[f] = wa, wb
        # rho is convex on each edge: its max is at a corner, and rho~ <= rho
        self.support_radius = np.zeros(len(self.centers))
        np.maximum.at(self.support_radius, self.edge_star, self.shrink * self._corner_r)
        # a lower bound of rho~ per star (for the phi radii of the general basis):
        # min of rho over the edge is p at the foot nu if inside, else at an end
        phi = np.clip(self.nu, 0.0, self.delta) - self.nu
        rmin = self.p / np.cos(phi)
        self.min_radius = np.full(len(self.centers), np.inf)
        np.minimum.at(self.min_radius, self.edge_star, self.shrink * self.kappa * rmin)

    def measured_kappa(self, per_edge=16):
        """min of rho~ / (shrink rho) on a uniform sample of angles of every edge."""
        E = len(self.delta)
        e = np.repeat(np.arange(E), per_edge)
        t = (np.tile(np.arange(per_edge), E) + 0.5) / per_edge * self.delta[e]
        rt = self.rho_tilde(e, t)[0]
        return float(np.min(rt / (self.shrink * self.p[e] / np.cos(t - self.nu[e]))))

    def u_tilde(self, e, t, nu=0):
        """U = 1/rho~ (after shrink) on edge e at angle t in [0, delta_e], with its
        t-derivatives up to ``nu``: list of arrays. Exact to rounding."""
        e = np.asarray(e)
        t = np.asarray(t, dtype=np.float64)
        if self.exact:
            ph = t - self.nu[e]
            k = 1.0 / (self.shrink * self.p[e])
            return [k * np.cos(ph), -k * np.sin(ph), -k * np.cos(ph)][: nu + 1]
        g, f = self.prev_edge[e], self.next_edge[e]
        left = (g >= 0) & (t < self.L[e])
        right = (f >= 0) & (t > self.delta[e] - self.R[e]) & ~left
        ia, ib = np.where(left, g, e), np.where(right, f, e)
        ta = np.where(left, t + self.delta[ia], t)
        tb = np.where(right, t - self.delta[e], t)
        width = np.where(left, self.R[ia] + self.L[e], np.where(right, self.R[e] + self.L[ib], 1.0))
        w = np.where(left, (t + self.R[ia]) / width,
                     np.where(right, (t - self.delta[e] + self.R[e]) / width, 0.0))
        w = np.clip(w, 0.0, 1.0)
        F = self.kernel.cdf_derivs(np.atleast_1d(w).ravel(), nu)
        F = [np.where(left | right, Fi.reshape(w.shape), 0.0) for Fi in F]
        ka = 1.0 / (self.shrink * self.c[ia] * self.p[ia])
        kb = 1.0 / (self.shrink * self.c[ib] * self.p[ib])
        pa, pb = ta - self.nu[ia], tb - self.nu[ib]
        A = [ka * np.cos(pa), -ka * np.sin(pa), -ka * np.cos(pa)]
        B = [kb * np.cos(pb), -kb * np.sin(pb), -kb * np.cos(pb)]
        D = [bi - ai for ai, bi in zip(A, B)]
        out = [A[0] + F[0] * D[0]]
        if nu >= 1:
            out.append(A[1] + F[0] * D[1] + F[1] / width * D[0])
        if nu >= 2:
            out.append(A[2] + F[0] * D[2] + 2 * F[1] / width * D[1] + F[2] / width ** 2 * D[0])
        return out

    def rho_tilde(self, e, t, nu=0):
        """The smooth radius rho~ (after shrink) on edge e at angle t in [0, delta_e],
        with its t-derivatives up to ``nu``: list of arrays."""
        u = self.u_tilde(e, t, nu)
        inv = 1.0 / u[0]
        out = [inv]
        if nu >= 1:
            out.append(-u[1] * inv ** 2)
        if nu >= 2:
            out.append(2 * u[1] ** 2 * inv ** 3 - u[2] * inv ** 2)
        return out

    # -- lookup and evaluation -------------------------------------------
    def _build_angle_index(self):
        E = len(self.delta)
        ang = np.arctan2(self.a0[:, 1], self.a0[:, 0])
        # reference angle per star: its first edge in index order
        first = np.full(len(self.centers), -1)
        first[self.edge_star[::-1]] = np.arange(E)[::-1]
        self._ref = np.where(first >= 0, ang[np.maximum(first, 0)], 0.0)
        rel = np.mod(ang - self._ref[self.edge_star], 2 * np.pi)
        rel[np.arange(E) == first[self.edge_star]] = 0.0
        key = self.edge_star * 8.0 + rel
        self._order = np.argsort(key, kind="stable")
        self._keys = key[self._order]

    def find_edges(self, x, star):
        """Edge of each star (M, K) whose angular sector contains x; -1 if none."""
        if not hasattr(self, "_keys"):
            self._build_angle_index()
        valid = star >= 0
        s = np.where(valid, star, 0)
        y = x[:, None, :] - self.centers[s]
        rel = np.mod(np.arctan2(y[..., 1], y[..., 0]) - self._ref[s], 2 * np.pi)
        pos = np.searchsorted(self._keys, s * 8.0 + rel, side="right") - 1
        pos = np.clip(pos, 0, len(self._keys) - 1)
        e = self._order[pos]
        ok = valid & (self.edge_star[e] == s)
        return np.where(ok, e, -1)

    def psi_jet(self, x, star, edge, nu=0):
        """psi (M, K) and its gradient (M, K, 2), Hessian (M, K, 2, 2) at x (M, 2)
        for the stars ``star`` (M, K) (-1 = empty slot, psi = 0) using boundary edge
        ``edge`` (M, K) (None: found by angle)."""
        if edge is None:
            edge = self.find_edges(x, star)
        valid = (star >= 0) & (edge >= 0)
        M, K = star.shape
        v = np.zeros((M, K))
        g = np.zeros((M, K, 2)) if nu >= 1 else None
        h = np.zeros((M, K, 2, 2)) if nu >= 2 else None
        if not valid.any():
            return v, g, h
        rows, cols = np.nonzero(valid)
        e = edge[rows, cols]
        y = x[rows] - self.centers[self.edge_star[e]]
        r_jet, t_jet = polar_jet(y, nu)
        r = r_jet[0]
        t = np.arctan2(_cross(self.a0[e], y), np.sum(self.a0[e] * y, -1))
        t = np.where(r > 0, t, 0.0)
        inside = (t >= -1e-12) & (t <= self.delta[e] + 1e-12)
        t_jet[0] = np.clip(t, 0.0, self.delta[e])      # the edge's angle: theta - const
        jet = bump_jet(self.kernel, star_gauge_jet(r_jet, t_jet, self.u_tilde(e, t_jet[0], nu),
                                                   nu), nu)
        v[rows, cols] = np.where(inside, jet[0], 0.0)
        live = inside & (r > 0)      # (beyond g = 1 the bump's derivatives are exactly 0)
        if nu >= 1:
            g[rows, cols] = np.where(live[:, None], jet[1], 0.0)
        if nu >= 2:
            h[rows, cols] = np.where(live[:, None, None], jet[2], 0.0)
        return v, g, h


def delaunay_triangulation(points):
    """scipy Delaunay with CCW simplices; raise InvalidPointSetError for degenerate sets."""
    if points.shape[1] != 2:
        raise InvalidParameterError("cover", "star covers are planar: points must have n = 2")
    if points.shape[0] < 3:
        raise InvalidPointSetError(f"points: a Delaunay cover needs >= 3 points, got {points.shape[0]}")
    try:
        tri = Delaunay(points)
    except QhullError as exc:
        raise InvalidPointSetError(
            "points: degenerate (collinear) point set, no Delaunay triangulation: "
            + str(exc).splitlines()[0], np.arange(points.shape[0])) from None
    if len(tri.coplanar):
        raise InvalidPointSetError("points: Qhull dropped these points (numerically coincident)",
                                   tri.coplanar[:, 0])
    s = tri.simplices.copy()
    nb = tri.neighbors.copy()
    P = points[s]
    area = _cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    neg = area < 0
    s[neg, 1], s[neg, 2] = s[neg, 2].copy(), s[neg, 1].copy()
    nb[neg, 1], nb[neg, 2] = nb[neg, 2].copy(), nb[neg, 1].copy()    # neighbour j is opposite vertex j
    return tri, s, nb


def _corner_in(s, tri_idx, vertex):
    """Edge index 3 t + k of the corner of triangle ``tri_idx`` at ``vertex`` (-1 if none)."""
    ok = tri_idx >= 0
    t = np.where(ok, tri_idx, 0)
    k = np.argmax(s[t] == vertex[:, None], axis=1)
    return np.where(ok, 3 * t + k, -1)


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
    cover = PlanarStarCover(points, star, points[i0], points[i1], nxt, prv, kernel, **gauge_kw)
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
    np.add.at(tot, star, _angle(q0 - c, q1 - c))
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
        keep = np.linalg.norm(cell - np.roll(cell, 1, axis=0), axis=1) > 1e-12 * (1 + np.abs(cell).max())
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
    if np.any(_cross(e, np.roll(e, -1, 0)) <= 0):
        raise InvalidParameterError("domain", "polygon must be convex and counter-clockwise")
    # points strictly inside
    rel = points[:, None, :] - domain[None]
    out = np.flatnonzero(np.any(_cross(e[None], rel) <= 0, axis=1))
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
    return _rings_cover(points, rings, kernel, **gauge_kw), domain


def in_convex_polygon(x, poly):
    e = np.roll(poly, -1, 0) - poly
    rel = x[:, None, :] - poly[None]
    return np.all(_cross(e[None], rel) >= 0, axis=1)
