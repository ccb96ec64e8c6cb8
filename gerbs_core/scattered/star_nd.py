"""Star-1 neighbourhoods of a Delaunay simplicialization in R^n (paper Example 2 case 1,
Example 8) with a smooth star gauge on the sphere S^(n-1) (DESIGN 4 in n dimensions).

The star of a vertex v is the union of the simplices S containing it. In S the
exact gauge of v (eq. (62) with the exact radial function) is linear,

    l_S(y) = 1 - lambda_v^S(v + y) = a_S . y,     y = x - v,

so the exact gauge is piecewise linear, kinked across the facets through v. The
smooth gauge blends the same linear pieces, pulled in by c = (1 + kappa)/2, with a
smooth partition of unity W_S on the sphere (positively homogeneous of degree 0):

    g~(y) = (1/shrink) sum_S W_S(y) l_S(y) / c,      W_S = w_S / sum_T w_T,
    w_S(y) = prod_{j != v} F((mu_j + delta_S) / delta_S),  mu_j = lambda_j^S(v+y) / l_S(y),

mu the barycentric coordinates, in the facet F_S opposite v, of the point where the ray
from v through x meets F_S's hyperplane; F the kernel CDF (C-infinity for ERBS). w_S = 1
on the closed cone over F_S and > 0 only in its delta_S-enlargement, so sum w >= 1 on
the star and W is smooth; psi = b(g~) (the chain rule of :mod:`.metrics`).

Certified bounds (no sampling). On the enlarged facet, in F_S's hyperplane, the
exact gauge g is within L D of 1 (L = max |a_T| over the star, the Lipschitz constant
of g; D = delta_S n max_j |q_j - q_bar| bounds the distance to F_S), and delta_S is
chosen with L D = (1 - kappa)/(1 + kappa), so every blended piece satisfies
g <= l_S/c <= g/kappa where W_S > 0, and by convexity of the blend

    g / shrink <= g~ <= g / (kappa shrink)        on the star.

The bound is conservative: Delaunay stars in R^3 have sharp kinks and slivers, so
the certified zones are narrow (median delta ~ 0.002-0.005 of the facet for random
points): psi is C-infinity, but its transitions across the facets are steep. The
values of the interpolant do not depend on this (a convex combination of Taylor
polynomials); its second derivatives do (see README).
Hence supp psi_v lies inside the star (at g <= shrink), and the cover is thick: in a
simplex max_v lambda_v >= 1/(n+1), so some g_v <= n/(n+1) and psi_v >= b(n/((n+1) kappa
shrink)) > 0 when kappa shrink > n/(n+1) (the default kappa is chosen so).
``exact=True`` uses g = l_S / shrink (kinked; tests only).
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..errors import InvalidParameterError, InvalidPointSetError
from ..gauge.jet import bump_derivs, chain_jet
from .partition import jmul, jsum, normalize
from .triangulation import delaunay

__all__ = ["DelaunayStarCover", "default_kappa"]


def default_kappa(n, shrink=0.95):
    """kappa with kappa * shrink halfway between n/(n+1) (the thickness limit) and 1."""
    t = n / (n + 1.0)
    return min(0.995, 0.5 * (1.0 + t) / shrink)


def _delaunay(points):
    N, n = points.shape
    if N < n + 1:
        raise InvalidPointSetError(f"points: a Delaunay cover in R^{n} needs >= {n + 1} points, got {N}")
    return delaunay(points)


def _barycentric_gradients(points, S):
    """G (T, n+1, n): grad lambda_j of every simplex (lambda = G (x - v_n) + e_n)."""
    n = points.shape[1]
    E = points[S[:, :n]] - points[S[:, n:]]                   # rows v_j - v_n, (T, n, n)
    try:
        with np.errstate(all="ignore"):
            Tinv = np.linalg.inv(E).transpose(0, 2, 1)       # lambda_j = Tinv_j . (x - v_n)
        # flat simplices: |grad lambda| * edge length ~ 1 / (relative height) explodes
        size = np.abs(E).max(axis=(1, 2))
        bad = ~(np.abs(Tinv).max(axis=(1, 2)) * size < 1e12)
    except np.linalg.LinAlgError:
        bad = np.ones(len(S), bool)
        bad[:] = [np.linalg.matrix_rank(e) < n for e in E]
    if bad.any():
        raise InvalidPointSetError("points: degenerate (flat) Delaunay simplices at points",
                                   np.unique(S[bad]))
    return np.concatenate([Tinv, -Tinv.sum(axis=1, keepdims=True)], axis=1)


def _jet_ratio(A, B, GA, GB):
    """Jet (value, gradient, Hessian) of mu = A/B for linear A, B with gradients GA, GB."""
    mu = A / B
    g = (GA - mu[..., None] * GB) / B[..., None]
    h = -(g[..., :, None] * GB[..., None, :] + GB[..., :, None] * g[..., None, :]) / B[..., None, None]
    return mu, g, h


class DelaunayStarCover:
    """Smooth star gauges of the Delaunay stars of points (N, n), n >= 2 (see module doc).

    Attributes: ``tri`` (:class:`~.triangulation.Triangulation`, Qhull's on normalised
    coordinates, answering in the caller's), ``simplices`` (T, n+1), ``G`` (T, n+1, n) the
    barycentric gradients, ``delta`` and ``scale`` c per corner (T*(n+1),) (corner
    t (n+1) + k: vertex k of simplex t), ``star_ptr``/``star_corners`` the corners of
    each star (CSR), ``lipschitz`` (N,) the exact gauge's Lipschitz constant per star
    (1 / the smallest facet distance), ``min_radius`` (N,) a lower bound of rho~ per
    star, ``support_radius`` (N,) an upper bound of the support's radius, ``max_gauge``
    (every point of the hull has some g~_v <= max_gauge = n / ((n+1) kappa shrink)),
    ``kappa``, ``shrink``.
    """

    def __init__(self, points, kernel, kappa=None, shrink=0.95, exact=False, tri=None, tree=None):
        N, n = points.shape
        self._tree = tree
        self.points, self.kernel, self.n, self.exact = points, kernel, n, bool(exact)
        if not (0 < shrink <= 1):
            raise InvalidParameterError("shrink", f"need 0 < shrink <= 1, got {shrink}")
        kappa = default_kappa(n, shrink) if kappa is None else float(kappa)
        if not (0 < kappa < 1):
            raise InvalidParameterError("kappa", f"need 0 < kappa < 1, got {kappa}")
        if kappa * shrink <= n / (n + 1.0):
            raise InvalidParameterError(
                "kappa", f"kappa * shrink = {kappa * shrink:.4g} must exceed n/(n+1) = "
                f"{n / (n + 1.0):.4g} for a thick cover in R^{n}")
        self.kappa, self.shrink = kappa, float(shrink)
        self.tri = _delaunay(points) if tri is None else tri
        S = self.simplices = self.tri.simplices
        self.G = _barycentric_gradients(points, S)
        self._corners()
        # thickness: in a simplex some g_v <= n/(n+1), and g~ <= g / (kappa shrink)
        inner = self.shrink if self.exact else self.kappa * self.shrink
        self.max_gauge = n / ((n + 1.0) * inner)

    @cached_property
    def support_radius(self) -> np.ndarray:
        """(N,) supp psi_v lies in the ball of this radius about v: shrink times the
        farthest vertex of v's star (g~ >= g / shrink, and the star is the set g < 1)."""
        S, P = self.simplices, self.points
        out = np.zeros(len(P))
        for a in range(self.n + 1):
            for b in range(a + 1, self.n + 1):
                d = np.linalg.norm(P[S[:, a]] - P[S[:, b]], axis=1)
                np.maximum.at(out, S[:, a], d)
                np.maximum.at(out, S[:, b], d)
        return self.shrink * out

    def _corners(self):
        """Per-star corner lists (CSR), the certified delta and c of every corner, and a
        circular cone about the facet centroid's direction containing its delta-zone
        (a cheap necessary test before the exact one)."""
        S, G, n = self.simplices, self.G, self.n
        T = len(S)
        flat = S.reshape(-1)                                  # corner c = t (n+1) + k
        order = np.argsort(flat, kind="stable")
        counts = np.bincount(flat, minlength=len(self.points))
        self.star_ptr = np.concatenate([[0], np.cumsum(counts)])
        self.star_corners = order
        inv_p = np.sqrt(np.einsum("tkn,tkn->tk", G, G))       # |a_S| = 1 / p_S, (T, n+1)
        starts = self.star_ptr[:-1][counts > 0]
        L = np.zeros(len(self.points))
        L[counts > 0] = np.maximum.reduceat(inv_p.reshape(-1)[order], starts)
        self.min_radius = np.full(len(self.points), np.inf)
        self.min_radius[counts > 0] = self.kappa * self.shrink / L[counts > 0]
        self.lipschitz = L
        V = [self.points[S[:, k]] for k in range(n + 1)]     # (T, n) per vertex slot
        tot = np.sum(V, axis=0)
        beta = (1.0 - self.kappa) / (1.0 + self.kappa)
        delta = np.empty((T, n + 1))
        axis = np.empty((T, n + 1, n))
        cos = np.ones((T, n + 1))

        def norm(a):
            return np.sqrt(np.einsum("tn,tn->t", a, a))

        for k in range(n + 1):
            qbar = (tot - V[k]) / n                           # centroid of the facet opposite v
            others = [j for j in range(n + 1) if j != k]
            off = {j: V[j] - qbar for j in others}
            spread = np.max([norm(off[j]) for j in others], axis=0)
            dk = beta / (L[S[:, k]] * n * spread)
            delta[:, k] = dk
            ax = qbar - V[k]
            ax /= norm(ax)[:, None]
            axis[:, k] = ax
            for j in others:                                  # zone vertices seen from v
                z = V[j] - V[k] + (dk * n)[:, None] * off[j]
                cos[:, k] = np.minimum(cos[:, k], np.einsum("tn,tn->t", z, ax) / norm(z))
        self.delta = delta.reshape(-1)
        self.scale = np.full(T * (n + 1), 1.0 if self.exact else 0.5 * (1.0 + self.kappa))
        self._axis = axis.reshape(-1, n)
        c = cos.reshape(-1)
        self._cos = np.where(c > 0, c * (1 - 1e-9) - 1e-12, -2.0)

    # ------------------------------------------------------------------ lookup
    def candidates(self, x):
        """Vertices (M, n+1) of the simplex containing each x (-1 outside the hull)."""
        t = self.locate(x)
        ok = t >= 0
        return np.where(ok[:, None], self.simplices[np.maximum(t, 0)], -1)

    def locate(self, x, tol=1e-12, max_steps=None):
        """Simplex (M,) containing each x, -1 outside the hull: a visibility walk (to the
        neighbour opposite the most negative barycentric coordinate, which terminates on
        Delaunay simplicializations) from a simplex of the nearest point, all queries at
        once; Qhull's find_simplex for any walk longer than ``max_steps``."""
        n, S = self.n, self.simplices
        if self._tree is None:
            from scipy.spatial import cKDTree
            self._tree = cKDTree(self.points)
        v = self._tree.query(x)[1]
        t = self.star_corners[self.star_ptr[v]] // (n + 1)
        out = np.full(len(x), -1)
        live = np.arange(len(x))
        nbr = self.tri.neighbors
        steps = max_steps or 20 + 4 * int(round(len(self.points) ** (1.0 / n)))
        for _ in range(steps):
            if not live.size:
                break
            tl = t[live]
            lam = np.einsum("mjn,mn->mj", self.G[tl], x[live] - self.points[S[tl, n]])
            lam[:, n] += 1.0
            j = np.argmin(lam, axis=1)
            inside = lam[np.arange(len(live)), j] >= -tol
            out[live[inside]] = tl[inside]
            nxt = nbr[tl, j]
            move = ~inside & (nxt >= 0)
            t[live[move]] = nxt[move]
            live = live[move]
        if live.size:
            out[live] = self.tri.find_simplex(x[live], tol=tol)
        return out

    def _pairs(self, verts):
        """Ragged (query slot, star corner) pairs for the slots ``verts`` (Q,) (>= 0)."""
        deg = self.star_ptr[verts + 1] - self.star_ptr[verts]
        slot = np.repeat(np.arange(len(verts)), deg)
        start = np.repeat(self.star_ptr[verts], deg)
        off = np.arange(len(slot)) - np.repeat(np.cumsum(deg) - deg, deg)
        return slot, self.star_corners[start + off]

    # --------------------------------------------------------------- the gauge
    def gauge_jet(self, y, verts, nu):
        """g~ of the stars ``verts`` (Q,) at offsets y (Q, n): value (Q,), gradient (Q, n),
        Hessian (Q, n, n) (None beyond ``nu``). Exact to rounding."""
        n, Q = self.n, len(verts)
        slot, corner = self._pairs(verts)
        yhat = y / np.linalg.norm(y, axis=1, keepdims=True)
        near = np.einsum("pn,pn->p", self._axis[corner], yhat[slot]) >= self._cos[corner]
        slot, corner = slot[near], corner[near]
        t, k = np.divmod(corner, n + 1)
        Gs = self.G[t]                                        # (P, n+1, n)
        lam = np.einsum("pjn,pn->pj", Gs, y[slot])            # lambda_j(v + y) - delta_jk
        rows = np.arange(len(slot))
        ell = -lam[rows, k]
        with np.errstate(divide="ignore", invalid="ignore"):
            mu = lam / ell[:, None]
        mu[rows, k] = np.inf
        live = (ell > 0) & np.all(mu >= -self.delta[corner][:, None], axis=1)
        if self.exact:
            live &= np.all(mu >= 0, axis=1)
        # first live corner per slot (the exact gauge), and the padded live lists
        slot, corner, t, k, Gs = slot[live], corner[live], t[live], k[live], Gs[live]
        counts = np.bincount(slot, minlength=Q)
        K = max(int(counts.max()) if Q else 1, 1)
        rank = np.arange(len(slot)) - np.repeat(np.cumsum(counts) - counts, counts)
        a = -Gs[np.arange(len(slot)), k]                      # grad l_S
        ys = y[slot]
        ell = np.einsum("pn,pn->p", a, ys)
        w = self._weights(Gs, k, a, ys, ell, corner, nu)
        c = self.scale[corner]
        u = (ell / c, a / c[:, None], np.zeros(a.shape + (n,)) if nu >= 2 else None)
        pad = [np.zeros((Q, K) + (n,) * i) for i in range(nu + 1)]
        Wp = [p.copy() for p in pad]
        Up = [p.copy() for p in pad]
        for i in range(nu + 1):
            Wp[i][slot, rank] = w[i]
            Up[i][slot, rank] = u[i]
        Wp += [None] * (2 - nu)
        Up += [None] * (2 - nu)
        with np.errstate(divide="ignore", invalid="ignore"):
            Wn = normalize(tuple(Wp), nu)
        Wn = tuple(None if a_ is None else np.nan_to_num(a_, nan=0.0) for a_ in Wn)
        g = list(jsum(jmul(Wn, tuple(Up), nu), nu))
        g[0] = np.where(counts > 0, g[0], np.inf)             # no live piece: outside the star
        return tuple(None if a_ is None else a_ / self.shrink for a_ in g)

    def _weights(self, Gs, k, a, ys, ell, corner, nu):
        """Jets of w_S = prod_j F((mu_j + delta)/delta) on the live pairs."""
        n = self.n
        P = len(k)
        one = (np.ones(P), np.zeros((P, n)) if nu >= 1 else None,
               np.zeros((P, n, n)) if nu >= 2 else None)
        if self.exact:
            return one
        w = one
        dl = self.delta[corner]
        rows = np.arange(P)
        for jj in range(n):
            j = np.where(jj < k, jj, jj + 1)                  # the facet vertices j != k
            Gj = Gs[rows, j]
            mu, mg, mh = _jet_ratio(np.einsum("pn,pn->p", Gj, ys), ell, Gj, a)
            s = (mu + dl) / dl
            inner = s < 1.0
            if not inner.any():
                continue
            F = self.kernel.cdf_derivs(np.clip(s, 0.0, 1.0), nu)
            f = [F[0]]
            if nu >= 1:
                f.append((F[1] / dl)[:, None] * mg)
            if nu >= 2:
                f.append((F[2] / dl ** 2)[:, None, None] * mg[:, :, None] * mg[:, None, :]
                         + (F[1] / dl)[:, None, None] * mh)
            f += [None] * (2 - nu)
            w = jmul(w, tuple(f), nu)
        return w

    def psi_jet(self, x, idx, nu):
        """psi (M, K), gradient (M, K, n), Hessian (M, K, n, n) of the stars idx (M, K)."""
        M, K = idx.shape
        n = self.n
        out = [np.zeros((M, K) + (n,) * i) for i in range(nu + 1)] + [None] * (2 - nu)
        valid = idx >= 0
        if not valid.any():
            return tuple(out)
        rows, cols = np.nonzero(valid)
        v = idx[rows, cols]
        y = x[rows] - self.points[v]
        at_centre = ~np.any(y != 0.0, axis=1)
        y = np.where(at_centre[:, None], 1.0, y)              # any direction: masked below
        g = list(self.gauge_jet(y, v, nu))
        g[0] = np.where(at_centre, 0.0, g[0])
        jet = chain_jet(bump_derivs(self.kernel, g[0], nu), g, nu)
        for i in range(nu + 1):
            val = jet[i]
            if i:
                val = np.where(at_centre.reshape((-1,) + (1,) * i), 0.0, val)
            out[i][rows, cols] = val
        return tuple(out)
