"""Planar star covers of scattered points: N star-shaped polygons with smooth gauges,
batched (paper section 5, DESIGN section 4).

:class:`PlanarStarCover` holds all N elements at once in flat arrays, because one
Python object per element (``gauge.StarGauge``) would cost ~N Python calls for
N = 10^5..10^6. It follows the gauge rule of DESIGN section 4 (same as
``gauge.StarGauge``):

* the exact radius of the polygon about its centre is piecewise
  rho(t) = p_e / cos(t - nu_e) on each boundary edge e, t the angle from the
  direction to the edge's first corner;
* u~ = 1/rho~ is a GERBS spline in the angle whose local functions are the edges'
  own lines u_e = cos(t - nu_e)/p_e, pulled in by c_e in [kappa, 1] (0.9-0.97
  next to convex corners, as close to 1 as lets their transitions fill the room:
  :func:`gerbs_core.gauge.blend.adaptive_scales`; 1 between reflex ones), with ONE
  transition per corner, as wide as certified (up to half of each adjacent edge, see
  ``_subdivide`` and :func:`gerbs_core.gauge.blend.blend_check`), so
  kappa rho <= rho~ <= rho; then rho~ is scaled by ``shrink`` = 0.95. One
  transition per corner (not knots at a staircase of constants) keeps the
  derivatives of rho~ of the size of the polygon's, not O(1) jumps within 1e-4.
  Evaluated by the one GERBS spline evaluator (:mod:`gerbs_core.splines.evaluate`).
* Thickness of the Delaunay cover is guaranteed: in a triangle the exact gauge of
  vertex a is 1 - lambda_a (barycentric), max lambda >= 1/3, and
  rho~ >= kappa shrink rho = 0.76 rho > 2/3 rho, so some psi_a >= b(0.667/0.76) > 0.
* g(x) = |x - c| / rho~(theta), psi = b(g). With a kernel flat at 0 and 1 (ERBS)
  rho~ and psi are C-infinity; supp psi lies strictly inside the polygon.
* ``exact=True`` uses shrink * rho (the kinked polygon radius): psi then has
  kinks along the corner rays (used by the tests to show the checks bite).
"""
from __future__ import annotations

import numpy as np

from ..errors import InvalidParameterError, InvalidPointSetError
from ..gauge.envelope_spline import line_jet, reciprocal_derivs
from ..gauge.jet import bump_jet, polar_jet, star_gauge_jet
from ..splines.evaluate import blend_jet, rising_jet

__all__ = ["PlanarStarCover", "cross2d", "signed_angle"]

_FIT_CHUNK = 1 << 16     # corners per width fit (its ~20 temporaries then stay in cache)
_TABLE_EDGES = 1 << 18   # covers up to this many edges keep u_tilde's row tables (~40k points)


def cross2d(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def dot2(a, b):
    """a . b over the last axis (..., 2): np.sum(a * b, -1) to the bit, 4x faster. (The
    + 0.0 keeps its +0.0 for (-0.0) + (-0.0): the sign of a zero decides arctan2.)"""
    return (a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1]) + 0.0


def norm2(a):
    """|a| over the last axis (..., 2), np.linalg.norm to the bit (5x faster)."""
    return np.sqrt(a[..., 0] * a[..., 0] + a[..., 1] * a[..., 1])


def signed_angle(a, b):
    """Signed angle from a to b in (-pi, pi]."""
    return np.arctan2(cross2d(a, b), dot2(a, b))


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
    domain_gauge : a bound of the polygons' exact gauge over the cover's domain (every
        point of it lies in some polygon scaled by domain_gauge about its centre: 2/3 for
        Delaunay stars in their hull, 1/2 for the doubled Voronoi cells in their domain),
        or None (user polygons: no domain known).

    ``max_gauge``: every domain point has some g~_i <= max_gauge = domain_gauge /
    (kappa shrink) (domain_gauge / shrink if ``exact``), so psi_i >= b(max_gauge); inf
    without ``domain_gauge``. ``support_radius`` (N,): supp psi_i lies in the disc of that
    radius about x_i; ``min_radius`` (N,): rho~_i >= min_radius_i in every direction.
    """

    def __init__(self, centers, edge_star, q0, q1, next_edge, prev_edge, kernel,
                 kappa=0.8, shrink=0.95, exact=False, domain_gauge=None):
        if not (0 < kappa < 1):
            raise InvalidParameterError("kappa", f"need 0 < kappa < 1, got {kappa}")
        if not (0 < shrink <= 1):
            raise InvalidParameterError("shrink", f"need 0 < shrink <= 1, got {shrink}")
        inner = shrink if exact else kappa * shrink          # rho~ >= inner * rho
        self.max_gauge = np.inf if domain_gauge is None else float(domain_gauge) / inner
        self.centers = centers
        self._centers_t = np.ascontiguousarray(centers.T)     # (psi_jet's gathers)
        self.kernel = kernel
        self.kappa, self.shrink, self.exact = float(kappa), float(shrink), bool(exact)
        self.edge_star = np.asarray(edge_star)
        self.next_edge = np.asarray(next_edge)
        self.prev_edge = np.asarray(prev_edge)
        self._edge_geometry(q0, q1)
        self._subdivide()

    def _edge_geometry(self, q0, q1):
        """Per edge: the corners a0, a1 relative to the centre, the corner radius, the
        angle delta, the line's distance p and foot angle nu.

        Coordinate-major (x and y rows (2, E), contiguous) and in place: the formulas of
        :func:`cross2d`, :func:`dot2`, :func:`norm2` and :func:`signed_angle` operation
        by operation (the same bits) with a few (E,) temporaries instead of ~30 (E,) and
        (E, 2) ones (at 10^5 points, E = 6 10^5: page faults of fresh memory were a third
        of this constructor's first call)."""
        es = self.edge_star
        cx, cy = self._centers_t[0][es], self._centers_t[1][es]
        q0x, q0y, q1x, q1y = q0[:, 0], q0[:, 1], q1[:, 0], q1[:, 1]
        self._a0t = a0 = np.empty((2, len(es)))
        self._a1t = a1 = np.empty((2, len(es)))
        np.subtract(q0x, cx, out=a0[0])
        np.subtract(q0y, cy, out=a0[1])
        np.subtract(q1x, cx, out=a1[0])
        np.subtract(q1y, cy, out=a1[1])
        (a0x, a0y), (a1x, a1y) = a0, a1
        ex, ey = np.subtract(q1x, q0x, out=cx), np.subtract(q1y, q0y, out=cy)   # e = q1 - q0
        del cx, cy

        def norm(x, y):
            out = np.multiply(x, x)
            out += y * y
            return np.sqrt(out, out=out)

        self._corner_r = np.maximum(norm(a0x, a0y), norm(a1x, a1y))
        cross = np.multiply(a0x, a1y)
        cross -= a0y * a1x
        dot = np.multiply(a0x, a1x)
        dot += a0y * a1y
        dot += 0.0
        self.delta = np.arctan2(cross, dot, out=dot)
        bad = np.flatnonzero(~(self.delta > 1e-12) | ~(self.delta < np.pi - 1e-12))
        if bad.size:
            raise InvalidPointSetError(
                "cover polygons are not star-shaped w.r.t. their points (edge seen under an angle "
                "outside (0, pi)); offending points", np.unique(self.edge_star[bad]))
        cross /= norm(ex, ey)
        self.p = cross
        # t = -dot2(a0, e) / dot2(e, e); foot = a0 + t e
        t = np.multiply(a0x, ex)
        t += a0y * ey
        t += 0.0
        np.negative(t, out=t)
        ee = np.multiply(ex, ex)
        ee += ey * ey
        ee += 0.0
        t /= ee
        fx = np.multiply(t, ex, out=ex)
        fx += a0x
        fy = np.multiply(t, ey, out=ey)
        fy += a0y
        # nu = signed_angle(a0, foot)
        num = np.multiply(a0x, fy, out=ee)
        num -= a0y * fx
        den = np.multiply(a0x, fx, out=t)
        den += a0y * fy
        den += 0.0
        self.nu = np.arctan2(num, den, out=num)

    @property
    def a0(self):
        """(E, 2) the edges' first corners relative to their star's centre (a view)."""
        return self._a0t.T

    @property
    def a1(self):
        """(E, 2) the edges' second corners relative to their star's centre (a view)."""
        return self._a1t.T

    # -- the envelope -----------------------------------------------------
    def _subdivide(self):
        """Corner transitions of the envelope (DESIGN section 4, same rule as
        :func:`gerbs_core.gauge.blend_ragged.build_blend`).

        u~ = 1/rho~ is a GERBS spline in the angle whose local functions are the
        edges' own lines u_e = cos(t - nu_e) / p_e pulled in by c_e (kappa <= c_e
        <= 1, from the edge's two corners: ``adaptive_scales``), blended across each
        corner over [delta_e - R_e, delta_e] of edge e and [0, L_f] of the next
        edge f: one transition per corner, initially half of each edge (the
        whole edge at an open end), narrowed until
        :func:`~gerbs_core.gauge.blend.blend_check` certifies
        kappa rho <= rho~/shrink <= rho on it (rigorous bound, not sampling).
        """
        from ..gauge.blend import fit_blend_widths, scales_from_corners
        E = len(self.delta)
        e = np.flatnonzero(self.next_edge >= 0)
        # the corners' arrays chunk by chunk, twice (scales, then widths), never all at
        # once: ~10 (E,) arrays less of fresh memory (their page faults cost more than
        # the repeated gathers); the same operations per corner, so the same bits
        chunks = [slice(s, s + _FIT_CHUNK) for s in range(0, len(e), _FIT_CHUNK)]
        self.c = scales_from_corners(E, (self._corners(e[k]) for k in chunks), self.kappa,
                                     self.kernel)
        self.R, self.L = np.zeros(E), np.zeros(E)
        bad = []
        for k in chunks:                  # per corner: chunks only keep it in cache
            ek, fk, nA, pA, nB, pB, roomA, roomB = self._corners(e[k])
            self.R[ek], self.L[fk], ok, _, _ = fit_blend_widths(
                nA, pA, self.c[ek], nB, pB, self.c[fk], roomA, roomB, self.kappa, self.kernel)
            bad.append(ek[~ok])
        bad = np.concatenate(bad) if bad else e[:0]
        if bad.size:
            raise InvalidPointSetError(
                "no certified smooth gauge at a corner of these stars (degenerate polygon); "
                "offending points", np.unique(self.edge_star[bad]))
        # the amplitude 1 / (shrink c p) of each edge's pulled-in line, once per edge
        self._line_scale = 1.0 / (self.shrink * self.c * self.p)
        self._sides = self._side_tables() if E <= _TABLE_EDGES and not self.exact else None
        # rho is convex on each edge: its max is at a corner, and rho~ <= rho
        self.support_radius = np.zeros(len(self.centers))
        np.maximum.at(self.support_radius, self.edge_star, self.shrink * self._corner_r)
        # a lower bound of rho~ per star (for the phi radii of the general basis):
        # min of rho over the edge is p at the foot nu if inside, else at an end
        phi = np.clip(self.nu, 0.0, self.delta) - self.nu
        rmin = self.p / np.cos(phi)
        self.min_radius = np.full(len(self.centers), np.inf)
        np.minimum.at(self.min_radius, self.edge_star, self.shrink * self.kappa * rmin)

    def _corners(self, e):
        """The corners at the ends of edges e (m,) (each into its next edge f):
        (e, f, nA, pA, nB, pB, roomA, roomB) of :func:`~gerbs_core.gauge.blend.adaptive_scales`,
        the rooms half of each edge (the whole edge at an open star's end)."""
        f = self.next_edge[e]
        de, df = self.delta[e], self.delta[f]
        nA, nB = self.nu[e] - de, self.nu[f]
        roomA = de * np.where(self.prev_edge[e] >= 0, 0.5, 1.0)
        roomB = df * np.where(self.next_edge[f] >= 0, 0.5, 1.0)
        return e, f, nA, self.p[e], nB, self.p[f], roomA, roomB

    def _side_tables(self):
        """The envelope's pieces on each edge e as two rows of flat tables, so that
        :meth:`u_tilde` gathers each quantity once by row and selects nothing:

        * row e: the transition into the next edge f (line e -> line f over
          [delta_e - R_e, delta_e + L_f]); also the middle of the edge, where its rise
          is set to 0 and the blend returns line e to the last bit (1 * A + 0 * B);
        * row E + e: the transition from the previous edge g (line g -> line e).

        Per row: line A (amplitude sA, angle mA, offset oA: evaluated at t - oA), line B
        (sB, mB, oB), the width and w2 (w = (t - oB + w2) / width), the lines' gauge
        vectors (ax, ay), (bx, by): t - (-d) is t + d
        to the bit, t - 0.0 is t, so every value is the direct formula's. thr_left /
        thr_right (per edge): the transitions' bounds L_e and delta_e - R_e (-inf / inf
        at an open star's ends). 24 floats per edge, ~65 ns per edge to build: worth it
        when the queries' (point, star) pairs outnumber the edges, so only for covers
        of up to _TABLE_EDGES edges (the direct formula otherwise, same bits)."""
        g, f = self.prev_edge, self.next_edge
        gs, fs = np.maximum(g, 0), np.maximum(f, 0)
        ls, m, d, R, L = self._line_scale, self.nu, self.delta, self.R, self.L
        names = ("sA", "mA", "oA", "sB", "mB", "oB", "width", "w2", "ax", "ay", "bx", "by")
        T = np.empty((len(names), 2, len(d)))
        sA, mA, oA, sB, mB, oB, width, w2, ax, ay, bx, by = T
        # the two lines' gauge vectors (:meth:`_gauge_values`): copies, so the same bits
        # as the direct formula's gathers
        vx, vy = self._line_vectors(np.arange(len(d)))
        ax[0], ay[0], bx[1], by[1] = vx, vy, vx, vy
        np.take(vx, gs, out=ax[1])
        np.take(vy, gs, out=ay[1])
        np.take(vx, fs, out=bx[0])
        np.take(vy, fs, out=by[0])
        sA[0], mA[0], sB[1], mB[1], oB[0], w2[0] = ls, m, ls, m, d, R
        oA[0], oB[1] = 0.0, 0.0
        np.take(ls, gs, out=sA[1])
        np.take(m, gs, out=mA[1])
        np.negative(np.take(d, gs, out=oA[1]), out=oA[1])
        np.take(ls, fs, out=sB[0])
        np.take(m, fs, out=mB[0])
        np.add(R, np.take(L, fs, out=width[0]), out=width[0])
        width[0][f < 0] = 1.0     # (an open star's end: only its middle, width 1 as there)
        np.add(np.take(R, gs, out=w2[1]), L, out=width[1])
        self._thr_left = np.where(g >= 0, L, -np.inf)
        self._thr_right = np.where(f >= 0, d - R, np.inf)
        return dict(zip(names, T.reshape(len(names), -1)))

    def measured_kappa(self, per_edge=16):
        """min of rho~ / (shrink rho) on a uniform sample of angles of every edge."""
        E = len(self.delta)
        e = np.repeat(np.arange(E), per_edge)
        t = (np.tile(np.arange(per_edge), E) + 0.5) / per_edge * self.delta[e]
        rt = self.rho_tilde(e, t)[0]
        return float(np.min(rt / (self.shrink * self.p[e] / np.cos(t - self.nu[e]))))

    def u_tilde(self, e, t, nu=0):
        """U = 1/rho~ (after shrink) on edge e at angle t in [0, delta_e], with its
        t-derivatives up to ``nu``: array (nu + 1, *t.shape). Exact to rounding.

        The GERBS spline of the edges' lines has one knot interval per corner, the
        transition [delta_e - R_e, delta_e + L_f] from edge e's line to the next edge
        f's, and between transitions the edge's own line (the same local function on
        both sides of an interval, so no blend)."""
        e = np.asarray(e)
        t = np.asarray(t, dtype=np.float64)
        if self.exact:
            return line_jet(1.0 / (self.shrink * self.p[e]), self.nu[e], None, t, nu)
        if self._sides is not None:
            k, ta, tb, rise = self._rows_rise(e, t, nu)
            S = self._sides
            A = line_jet(S["sA"][k], S["mA"][k], None, ta, nu)
            B = line_jet(S["sB"][k], S["mB"][k], None, tb, nu)
        else:
            ia, ib, ta, tb, rise = self._direct_rise(e, t, nu)
            A = line_jet(self._line_scale[ia], self.nu[ia], None, ta, nu)
            B = line_jet(self._line_scale[ib], self.nu[ib], None, tb, nu)
        return blend_jet(A, B, rise, nu)

    def _direct_rise(self, e, t, nu):
        """The corner transition at angle t (*S) of edge e (*S), by the direct formula:
        the edges of the two lines ia, ib, their angles ta, tb and the rising jet
        (nu + 1, *S) of the blend (0 between transitions)."""
        g, f = self.prev_edge[e], self.next_edge[e]
        Le, Re, de = self.L[e], self.R[e], self.delta[e]       # each gathered once
        left = (g >= 0) & (t < Le)
        right = (f >= 0) & (t > de - Re) & ~left
        ia, ib = np.where(left, g, e), np.where(right, f, e)
        Ra = self.R[ia]
        ta = np.where(left, t + self.delta[ia], t)
        tb = np.where(right, t - de, t)
        width = np.where(left, Ra + Le, np.where(right, Re + self.L[ib], 1.0))
        w = np.where(left, (t + Ra) / width,
                     np.where(right, (t - de + Re) / width, 0.0))
        rise = rising_jet(self.kernel, np.clip(w, 0.0, 1.0), width, nu)
        return ia, ib, ta, tb, np.where(left | right, rise, 0.0)

    def _rows_rise(self, e, t, nu):
        """:meth:`_direct_rise` from the rows of :meth:`_side_tables` (the same bits): the
        row k (*S) instead of the two edges."""
        left = t < self._thr_left[e]
        right = (t > self._thr_right[e]) & ~left
        k = e + len(self.delta) * left                     # the row
        S = self._sides
        width, tb = S["width"][k], t - S["oB"][k]
        rise = rising_jet(self.kernel, np.clip((tb + S["w2"][k]) / width, 0.0, 1.0), width, nu)
        return k, t - S["oA"][k], tb, np.where(left | right, rise, 0.0)

    def _gauge_values(self, e, t, y0, y1):
        """The smooth gauge g = r u~ (values only) at offsets y = (y0, y1) (*S) from the
        centre, at angle t (*S) of edge e (*S) (not ``exact``).

        Each line's r u_e = r cos(t - nu_e) / (shrink c_e p_e) is linear in y (:meth:`_line_vectors`),
        so the blend (1 - F) r u_A + F r u_B needs no cosines (and no r): the same
        values as r :meth:`u_tilde` up to rounding."""
        if self._sides is not None:
            k, _, _, rise = self._rows_rise(e, t, 0)
            S = self._sides
            gA = y0 * S["ax"][k] + y1 * S["ay"][k]
            gB = y0 * S["bx"][k] + y1 * S["by"][k]
        else:
            ia, ib, _, _, rise = self._direct_rise(e, t, 0)
            (ax, ay), (bx, by) = self._line_vectors(ia), self._line_vectors(ib)
            gA = y0 * ax + y1 * ay
            gB = y0 * bx + y1 * by
        F = rise[0]
        return (1.0 - F) * gA + F * gB

    def _line_vectors(self, e):
        """(vx, vy) (*S) of edges e (*S): r u_e = r cos(t - nu_e) / (shrink c_e p_e) = y . v_e,
        v_e the foot of the edge's line over p_e times its amplitude. Per queried edge (the
        same formula for the row tables and the direct path: the same bits), so that no
        (E,) array is built with the cover (large covers query a few of their edges)."""
        a0x, a0y, a1x, a1y = self._a0t[0][e], self._a0t[1][e], self._a1t[0][e], self._a1t[1][e]
        ex, ey = a1x - a0x, a1y - a0y
        t = -(a0x * ex + a0y * ey) / (ex * ex + ey * ey)
        s = self._line_scale[e] / self.p[e]
        return (a0x + t * ex) * s, (a0y + t * ey) * s

    def rho_tilde(self, e, t, nu=0):
        """The smooth radius rho~ (after shrink) on edge e at angle t in [0, delta_e],
        with its t-derivatives up to ``nu``: array (nu + 1, *t.shape)."""
        return reciprocal_derivs(self.u_tilde(e, t, nu))

    # -- lookup and evaluation -------------------------------------------
    def _build_angle_index(self):
        E = len(self.delta)
        ang = np.arctan2(self._a0t[1], self._a0t[0])
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
        # y = x - the edge's star centre, coordinate-major (no (M, K, 2) gathers)
        cx, cy = self._centers_t
        if valid.all():          # (Delaunay candidates inside the hull): no gather/scatter
            e = edge.reshape(-1)
            c = self.edge_star[e]
            y0 = (x[:, 0, None] - cx[c].reshape(M, K)).reshape(-1)
            y1 = (x[:, 1, None] - cy[c].reshape(M, K)).reshape(-1)
            put = (slice(None),)
            v, g, h = (a.reshape((-1,) + a.shape[2:]) if a is not None else None for a in (v, g, h))
        else:
            rows, cols = np.nonzero(valid)
            e = edge[rows, cols]
            c = self.edge_star[e]
            y0, y1 = x[rows, 0] - cx[c], x[rows, 1] - cy[c]
            put = (rows, cols)
        fast = nu == 0 and not self.exact     # values: the gauge without r (_gauge_values)
        if nu >= 1:
            r_jet, t_jet = polar_jet(np.stack([y0, y1], -1), nu)
        elif fast:               # (only r > 0 is needed: r^2 > 0 alike, NaN included)
            r_jet, t_jet = [y0 * y0 + y1 * y1], [None]
        else:                    # values: the edge angle below is the only angle needed
            r_jet, t_jet = [np.hypot(y0, y1)], [None]
        r = r_jet[0]
        a0x, a0y = self._a0t[0][e], self._a0t[1][e]
        # the angle from the edge's first corner: arctan2(cross2d(a0, y), dot2(a0, y))
        t = np.arctan2(a0x * y1 - a0y * y0, (a0x * y0 + a0y * y1) + 0.0)
        t = np.where(r > 0, t, 0.0)
        de = self.delta[e]
        inside = (t >= -1e-12) & (t <= de + 1e-12)
        t_jet[0] = np.clip(t, 0.0, de)      # the edge's angle: theta - const
        if fast:
            g = self._gauge_values(e, t_jet[0], y0, y1)
            # where t was clipped (within 1e-12 of the sector) y's direction is not the
            # angle's: there r u~(clipped t), as below (at hull edges: 1e-13 of B otherwise)
            off = np.flatnonzero(t != t_jet[0])
            if off.size:
                g[off] = np.hypot(y0[off], y1[off]) * self.u_tilde(e[off], t_jet[0][off], 0)[0]
            jet = bump_jet(self.kernel, [g], 0)
        else:
            jet = bump_jet(self.kernel, star_gauge_jet(r_jet, t_jet, self.u_tilde(e, t_jet[0], nu),
                                                       nu), nu)
        v[put] = np.where(inside, jet[0], 0.0)
        live = inside & (r > 0)      # (beyond g = 1 the bump's derivatives are exactly 0)
        if nu >= 1:
            g[put] = np.where(live[:, None], jet[1], 0.0)
        if nu >= 2:
            h[put] = np.where(live[:, None, None], jet[2], 0.0)
        if len(put) == 1:
            v, g, h = (a.reshape((M, K) + a.shape[1:]) if a is not None else None for a in (v, g, h))
        return v, g, h
