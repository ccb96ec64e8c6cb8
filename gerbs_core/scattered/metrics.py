"""Metrics of paper section 2.5.1 and the size/non-degeneracy bumps built on them.

Every metric answers three questions for the general construction (DESIGN 3):

* ``dist(x, y)``: d(x, y) for arrays ``(..., n)``;
* ``bump_jet(y, R, kernel, nu)``: the value, gradient and Hessian in ``y = x - x_i``
  of the bump of "radius" R about x_i: ``b(d(y)/R)`` for the radial metrics
  (eq. (39)), ``b(dt(y)/R)`` with dt = d/(1+d) (eq. (40), see :class:`Bounded`), or
  the tensor-product GERBS (41) for l_inf and l_1;
* ``coord_bound(R)``: per-coordinate half widths (n,) of a box containing the ball
  of radius R (used for KD-tree candidate search, Remark 12);
* ``tree_coords(x)`` / ``tree_p``: coordinates and Minkowski exponent in which a
  cKDTree computes d exactly (None when it cannot, e.g. quasi-norms).

Smoothness of the bump (derivatives supported by ``bump_jet``):

=====================  ===========================  ==========================
metric                 bump smoothness              ``max_nu``
=====================  ===========================  ==========================
Euclidean (weighted)   C-inf (kernel permitting)    2
l_p, p >= 2            C^2 at least (C-inf p even)  2
l_p, 1 < p < 2         C^1 (|t|^p at t=0)           1
l_inf (tensor (41))    C-inf                        2
l_1 (tensor (41))      C-inf                        2
quasi-norm 0 < p < 1   C^0 (|t|^p at t=0)           0
Bounded(base)          that of ``base``             that of ``base``
=====================  ===========================  ==========================

Everything is exact (closed form) up to rounding; the bump is flat at y = 0 for
kernels flat at 0 (ERBS), so the singularity of d at 0 does not show.
"""
from __future__ import annotations

import itertools

import numpy as np

from ..errors import InvalidParameterError
from ..gauge.jet import bump_derivs, chain_jet

__all__ = ["Metric", "Euclidean", "Lp", "LInf", "L1", "QuasiNorm", "Bounded"]


def _weights(weights, n):
    if weights is None:
        return np.ones(n)
    w = np.asarray(weights, dtype=float)
    if w.ndim == 0:
        w = np.full(n, float(w))
    if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise InvalidParameterError("weights", f"need {n} finite positive weights, got {w!r}")
    return w


def _triple(jet):
    """A jet list as the (value, gradient, Hessian) triple with None for orders not asked."""
    return tuple(jet) + (None,) * (3 - len(jet))


class Metric:
    """Base class; subclasses set ``n`` (dimension) and ``max_nu``."""

    max_nu = 2
    tree_p = 2.0

    def __init__(self, n: int):
        if int(n) < 1:
            raise InvalidParameterError("n", f"dimension must be >= 1, got {n}")
        self.n = int(n)

    def __repr__(self):
        p = f", p={self.p:g}" if hasattr(self, "p") else ""
        w = getattr(self, "w", None)
        w = "" if w is None or np.all(w == 1.0) else f", weights={w.tolist()}"
        return f"{type(self).__name__}(n={self.n}{p}{w})"

    def _check(self, y):
        y = np.asarray(y, dtype=float)
        if y.shape[-1] != self.n:
            raise InvalidParameterError("x", f"last axis must have length {self.n}, got shape {y.shape}")
        return y

    def dist(self, x, y):
        """d(x, y), shape of the broadcast leading axes."""
        return self.norm(self._check(x) - self._check(y))

    def check_nu(self, nu):
        if nu > self.max_nu:
            raise InvalidParameterError(
                "nu", f"{type(self).__name__} bumps are only C^{self.max_nu}: nu <= {self.max_nu}")

    # radial metrics: bump = b(norm(y)/R)
    def bump_jet(self, y, R, kernel, nu=0):
        """(value, gradient, Hessian) of the bump of radius R at offsets ``y`` (..., n).

        ``R`` broadcasts against the leading axes of ``y``. Gradient/Hessian are None
        when not requested.
        """
        self.check_nu(nu)
        d, dg, dh = self.norm_jet(y, nu)
        R = np.asarray(R, dtype=float)
        t = d / R
        t_jet = [t, dg / R[..., None] if nu >= 1 else None,
                 dh / R[..., None, None] if nu >= 2 else None]
        return _triple(chain_jet(bump_derivs(kernel, t, nu), t_jet, nu))

    def coord_bound(self, R):
        return np.asarray(R, float)[..., None] / self.w

    def tree_coords(self, x):
        return np.asarray(x, float) * self.w

    def gauge(self, y, R):
        """The bump's argument t at offsets y (..., n) for radii R (broadcast against the
        leading axes): bump = b(t) for the radial bumps, >= b(t)^m for the tensor bumps
        (41) (m factors, each >= b(t)); t < 1 exactly in the ball."""
        return self.norm(y) / np.asarray(R, float)

    def certified_gauge(self, margin, Rb):
        """The largest :meth:`gauge` of a point within base distance margin * Rb of a
        centre (base radii Rb (N,)): ``margin`` for a norm."""
        return float(margin)

    # support geometry, used by the ball search and the cover certificate
    convex = True          # balls are convex (a norm): a simplex lies in the ball of its vertices

    @property
    def base(self):
        """The norm whose balls are this metric's balls (itself, except for Bounded)."""
        return self

    def base_radius(self, R):
        """Radius in ``base`` of the ball of radius R (R itself for a norm)."""
        return np.asarray(R, float)

    def from_base_radius(self, Rb):
        """Inverse of :meth:`base_radius`."""
        return np.asarray(Rb, float)

    def search_radius(self, Rb):
        """(radius, Minkowski p) of a ball in ``tree_coords`` containing the base ball of
        radius Rb: exact for the l_p norms, the circumscribed l_2 ball otherwise."""
        return np.asarray(Rb, float), self.tree_p


class Euclidean(Metric):
    """(Weighted) Euclidean norm |y| = sqrt(sum (w_k y_k)^2), cases 0.0.0.0 / 0.0.0.1."""

    def __init__(self, n, weights=None):
        super().__init__(n)
        self.w = _weights(weights, self.n)

    def norm(self, y):
        return np.sqrt(np.sum((y * self.w) ** 2, axis=-1))

    def norm_jet(self, y, nu):
        w2 = self.w ** 2
        d = self.norm(y)
        if nu == 0:
            return d, None, None
        safe = np.where(d > 0, d, 1.0)
        g = (w2 * y) / safe[..., None]
        g[d == 0] = 0.0
        h = None
        if nu >= 2:
            h = (np.diag(w2) - g[..., :, None] * g[..., None, :]) / safe[..., None, None]
            h[d == 0] = 0.0
        return d, g, h


class Lp(Metric):
    """(Weighted) l_p norm, 1 < p < inf (cases 0.0.1.x); C^2 bumps need p >= 2."""

    def __init__(self, n, p, weights=None):
        super().__init__(n)
        p = float(p)
        if not (1.0 < p < np.inf):
            raise InvalidParameterError("p", f"Lp needs 1 < p < inf (use L1/LInf/QuasiNorm), got {p}")
        self.p = p
        self.tree_p = p
        self.w = _weights(weights, self.n)
        self.max_nu = 2 if p >= 2.0 else 1

    def norm(self, y):
        return np.sum(np.abs(y * self.w) ** self.p, axis=-1) ** (1.0 / self.p)

    def norm_jet(self, y, nu):
        p, w = self.p, self.w
        z = y * w
        az = np.abs(z)
        S = np.sum(az ** p, axis=-1)
        d = S ** (1.0 / p)
        if nu == 0:
            return d, None, None
        pos = S > 0
        Ss = np.where(pos, S, 1.0)
        dS = p * np.sign(z) * az ** (p - 1) * w            # dS/dy
        g = (1.0 / p) * (Ss ** (1.0 / p - 1.0))[..., None] * dS
        g[~pos] = 0.0
        h = None
        if nu >= 2:
            d2S = p * (p - 1) * az ** (p - 2) * w ** 2
            H = np.zeros(y.shape + (self.n,))
            idx = np.arange(self.n)
            H[..., idx, idx] = d2S
            c1 = (1.0 / p) * Ss ** (1.0 / p - 1.0)
            c2 = (1.0 / p) * (1.0 / p - 1.0) * Ss ** (1.0 / p - 2.0)
            h = c1[..., None, None] * H + c2[..., None, None] * dS[..., :, None] * dS[..., None, :]
            h[~pos] = 0.0
        return d, g, h


class _Tensor(Metric):
    """Tensor-product GERBS (41) over the facet normals ``A`` (m, n) of a polytope ball.

    bump(y) = prod_k b((A z)_k / R), z = w*y; support = {max_k |(A z)_k| < R}.
    """

    tree_p = np.inf

    def bump_jet(self, y, R, kernel, nu=0):
        R = np.asarray(R, dtype=float)
        u = (y * self.w) @ self.A.T / R[..., None]             # (..., m)
        Aw = self.A * self.w                                      # du/dy = Aw / R
        bt = bump_derivs(kernel, np.abs(u), nu)
        s = np.sign(u)
        f = [bt[0]]
        if nu >= 1:
            f.append(s * bt[1])
        if nu >= 2:
            f.append(bt[2])
        m = self.A.shape[0]
        v = np.prod(f[0], axis=-1)
        if nu == 0:
            return v, None, None
        # product rule over the m factors, each factor depends on y through u_k
        g = np.zeros(y.shape)
        h = np.zeros(y.shape + (self.n,)) if nu >= 2 else None
        for k in range(m):
            others = np.prod(np.delete(f[0], k, axis=-1), axis=-1)
            a = Aw[k] / R[..., None]
            g += (others * f[1][..., k])[..., None] * a
            if nu >= 2:
                h += (others * f[2][..., k])[..., None, None] * a[..., :, None] * a[..., None, :]
                for j in range(k + 1, m):
                    oth2 = np.prod(np.delete(f[0], [k, j], axis=-1), axis=-1)
                    aj = Aw[j] / R[..., None]
                    c = (oth2 * f[1][..., k] * f[1][..., j])[..., None, None]
                    h += c * (a[..., :, None] * aj[..., None, :] + aj[..., :, None] * a[..., None, :])
        return v, g, h

    def coord_bound(self, R):
        return np.asarray(R, float)[..., None] / self.w

    def search_radius(self, Rb):
        if self.tree_p == 1.0:
            return np.asarray(Rb, float), 1.0
        return np.sqrt(self.n) * np.asarray(Rb, float), 2.0


class LInf(_Tensor):
    """(Weighted) l_inf, case 0.1.0: bump = prod_k b(w_k y_k / R), eq. (41)."""

    def __init__(self, n, weights=None):
        super().__init__(n)
        self.w = _weights(weights, self.n)
        self.A = np.eye(self.n)

    def norm(self, y):
        return np.max(np.abs(y * self.w), axis=-1)


class L1(_Tensor):
    """(Weighted) l_1, case 0.1.1, by a tensor-product GERBS after a linear map.

    |z|_1 = max over sign vectors s (s_1 = +1) of |s . z|. In n = 2 this is eq. (41)
    after the rotation by 45 degrees and scaling by sqrt(2): u = (z1 + z2, z1 - z2),
    |z|_1 = |u|_inf. For n > 2 the cross-polytope is not an affine cube, so we take
    the product of b over all 2^(n-1) facet-normal pairs s: still C-inf, support
    exactly the l_1 ball (n = 1: just b(|z|/R)).
    """

    tree_p = 1.0

    def __init__(self, n, weights=None):
        super().__init__(n)
        self.w = _weights(weights, self.n)
        signs = [(1.0,) + s for s in itertools.product((1.0, -1.0), repeat=self.n - 1)]
        self.A = np.array(signs)

    def norm(self, y):
        return np.sum(np.abs(y * self.w), axis=-1)


class QuasiNorm(Metric):
    """Metric d(x,y) = sum_k |w_k (x_k - y_k)|^p, 0 < p < 1 (eq. (37), case 1.0).

    The bump b(d/R) is only C^0 (|t|^p is not differentiable at 0), so
    ``max_nu = 0``. A cKDTree cannot compute d, so ``tree_p`` is None and
    neighbour searches use the coordinate box bound |w_k y_k| <= d^(1/p).
    """

    max_nu = 0
    tree_p = None

    def __init__(self, n, p, weights=None):
        super().__init__(n)
        p = float(p)
        if not (0.0 < p < 1.0):
            raise InvalidParameterError("p", f"QuasiNorm needs 0 < p < 1, got {p}")
        self.p = p
        self.w = _weights(weights, self.n)

    def norm(self, y):
        return np.sum(np.abs(y * self.w) ** self.p, axis=-1)

    def norm_jet(self, y, nu):
        return self.norm(y), None, None

    def coord_bound(self, R):
        return np.asarray(R, float)[..., None] ** (1.0 / self.p) / self.w

    convex = False

    def search_radius(self, Rb):
        return np.sqrt(self.n) * np.asarray(Rb, float) ** (1.0 / self.p), 2.0


class Bounded(Metric):
    """dt = d/(1+d) for a base metric d (eq. (38), case 1.1).

    Eq. (40) as typeset, b(t/(1+t)) with t = |x - x_i|/rho, is never compactly
    supported (t/(1+t) < 1). We use the bump of the metric dt itself,
    b(dt(y)/R) with 0 < R < 1, whose support is the base ball of radius R/(1-R).
    """

    def __init__(self, base: Metric):
        super().__init__(base.n)
        if isinstance(base, Bounded):
            raise InvalidParameterError("metric", "the base of a bounded metric is itself bounded")
        self._base = base
        self.max_nu = base.max_nu
        self.tree_p = base.tree_p
        self.w = base.w
        self.convex = base.convex

    @property
    def base(self):
        return self._base

    def __repr__(self):
        return f"Bounded({self._base!r})"

    def base_radius(self, R):
        R = self._radius(R)
        return R / (1.0 - R)

    def from_base_radius(self, Rb):
        Rb = np.asarray(Rb, float)
        return Rb / (1.0 + Rb)

    def search_radius(self, Rb):
        return self.base.search_radius(Rb)

    def norm(self, y):
        d = self.base.norm(y)
        return d / (1.0 + d)

    def _radius(self, R):
        R = np.asarray(R, dtype=float)
        if np.any(R >= 1.0):
            raise InvalidParameterError("R", "radii of the bounded metric d/(1+d) must be < 1")
        return R

    def norm_jet(self, y, nu):
        d, g, h = self.base.norm_jet(y, nu)
        q = 1.0 / (1.0 + d)
        dt = d * q
        if nu == 0:
            return dt, None, None
        gt = (q ** 2)[..., None] * g
        ht = None
        if nu >= 2:
            ht = (q ** 2)[..., None, None] * h - (2 * q ** 3)[..., None, None] * g[..., :, None] * g[..., None, :]
        return dt, gt, ht

    def bump_jet(self, y, R, kernel, nu=0):
        """b(dt(y)/R) for a smooth base norm (eq. (40) read as the bump of dt); for an
        l_inf / l_1 base (no radial form) the base's tensor bump (41) of the same
        support, the base ball of radius R/(1-R)."""
        if isinstance(self.base, _Tensor):
            return self.base.bump_jet(y, self.base_radius(R), kernel, nu)
        return super().bump_jet(y, self._radius(R), kernel, nu)

    def coord_bound(self, R):
        R = self._radius(R)
        return self.base.coord_bound(R / (1.0 - R))

    def gauge(self, y, R):
        if isinstance(self.base, _Tensor):       # (the base's tensor bump, bump_jet)
            return self.base.gauge(y, self.base_radius(R))
        return self.norm(y) / np.asarray(R, float)

    def certified_gauge(self, margin, Rb):
        """dt/R for d <= margin Rb: up to margin (1 + Rb) / (1 + margin Rb), which tends
        to 1 for large base radii (the bounded metric is not scale invariant)."""
        if isinstance(self.base, _Tensor):
            return float(margin)
        Rb = np.asarray(Rb, float)
        return float(np.max(margin * (1.0 + Rb) / (1.0 + margin * Rb), initial=margin))

    def tree_coords(self, x):
        return self.base.tree_coords(x)
