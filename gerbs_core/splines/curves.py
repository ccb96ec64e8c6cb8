"""Univariate GERBS splines: the basis of eq. (3) and curves c = sum_j G_j l_j.

End convention (the paper's, Definition 2): the knot vector is
t_0 < t_1 < ... < t_n < t_{n+1} (``knots``, length n + 2) and there are n basis
functions G_1..G_n (columns 0..n-1 of the output), G_j supported on
[t_{j-1}, t_{j+1}]:

    G_j(t) = F_j(t)       for t in (t_{j-1}, t_j],
           = 1 - F_{j+1}(t) for t in (t_j, t_{j+1}),
           = 0            elsewhere,

with F_k(t) = F((t - t_{k-1}) / (t_k - t_{k-1})) the kernel CDF moved to the
knot interval [t_{k-1}, t_k]. Intervals are half-open (t_k, t_{k+1}] so that a
left-continuous kernel (Step) gives left-continuous G_j. Properties (Lemma 3):
sum_j G_j = 1 on [t_1, t_n] (up to one rounding), 0 <= G_j <= 1,
G_j(t_k) = delta_jk for k = 1..n. Outside [t_1, t_n], G_1 and G_n fall to 0
at t_0 and t_{n+1}: the curve with constant coefficients is the closed polygon
0 -> P_1 -> ... -> P_n -> 0 of Lemma 3 (iv) on the whole line, and exactly the
control polygon P_1 -> ... -> P_n on [t_1, t_n].

The kernel may differ per knot interval (e.g. BFBS(i_k, i_{k+1}) of
Definition 4): pass a sequence of n + 1 kernels, one per interval [t_k, t_{k+1}].

Derivatives: G_j^(nu) on the interval [t_k, t_{k+1}] of length h is
+-F^(nu)(s) / h^nu (chain rule, exact given the kernel's derivatives). Values and
derivatives come from the one GERBS spline evaluator, :mod:`.evaluate`.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import InvalidParameterError
from ..immutable import Immutable
from ..inputs import check_index, real_array
from ..kernels import Kernel, as_kernel
from ..kernels.base import as_float_array, check_order
from .evaluate import blend_jet, falling_jet, knot_interval, rising_jet

__all__ = ["GERBSBasis", "GERBSCurve"]


def _check_knots(knots) -> np.ndarray:
    k = real_array("knots", knots)
    if k.ndim != 1:
        raise InvalidParameterError("knots", f"must be a 1-d array, got shape {k.shape}")
    if k.size < 3:
        raise InvalidParameterError(
            "knots", f"need at least 3 knots (t_0, t_1, t_2) for one basis function, got {k.size}")
    bad = np.flatnonzero(~np.isfinite(k))
    if bad.size:
        err = InvalidParameterError("knots", f"non-finite knots at indices {bad.tolist()[:10]}")
        err.indices = tuple(int(i) for i in bad)
        raise err
    bad = np.flatnonzero(np.diff(k) <= 0.0)
    if bad.size:
        pairs = ", ".join(f"({i}, {i + 1})" for i in bad[:10].tolist())
        err = InvalidParameterError(
            "knots", f"must be strictly increasing; not increasing at index pairs {pairs}")
        err.indices = tuple(int(i) + 1 for i in bad)
        raise err
    k.setflags(write=False)
    return k


def _check_kernels(kernel, n_intervals: int):
    """(one kernel per interval, the single kernel or None): ``kernel`` a kernel or a name
    (:func:`~gerbs_core.kernels.as_kernel`), or a sequence of n_intervals of them."""
    if kernel is None or isinstance(kernel, (Kernel, str, bytes)) or \
            not isinstance(kernel, Sequence):
        one = as_kernel(kernel)
        return (one,) * n_intervals, one
    ks = tuple(kernel)
    if len(ks) != n_intervals:
        raise InvalidParameterError(
            "kernel", f"need one kernel per knot interval ({n_intervals}), got {len(ks)}")
    out = []
    for i, k in enumerate(ks):
        try:
            out.append(as_kernel(k))
        except InvalidParameterError as exc:
            err = InvalidParameterError("kernel", f"entry {i} {str(exc)[len('kernel: '):]}")
            raise err from None
    return tuple(out), None


def _kernel_repr(basis) -> str:
    """The kernel part of a repr: the common kernel, or a count of per-interval ones."""
    if basis._kernel is not None:
        return repr(basis._kernel)
    kinds = sorted({type(k).__name__ for k in basis._kernels})
    return f"<{len(basis._kernels)} per interval: {', '.join(kinds)}>"


class GERBSBasis(Immutable):
    """The GERBS basis G_1..G_n of eq. (3) on knots t_0 < ... < t_{n+1}.

    Parameters
    ----------
    knots : (n + 2,) strictly increasing floats (n >= 1).
    kernel : Kernel or its name (:func:`~gerbs_core.kernels.as_kernel`), or a sequence
        of n + 1 of them (one per knot interval). Default ERBS().

    ``basis(t, nu=0)`` -> array (*t.shape, n): G_j^(nu)(t) for j = 1..n.
    Exactness: as exact as the kernel (ERBS values ~1e-15, derivatives to
    rounding); the sum is 1 on [t_1, t_n] up to one rounding.
    """

    def __init__(self, knots, kernel: Kernel | Sequence[Kernel] | None = None):
        self._knots = _check_knots(knots)
        self._kernels, self._kernel = _check_kernels(kernel, self._knots.size - 1)
        self._h = np.diff(self._knots)
        self._h.setflags(write=False)
        self._freeze()

    @property
    def knots(self) -> np.ndarray:
        """(n + 2,) the knot vector t_0..t_{n+1} (read-only)."""
        return self._knots

    @property
    def n(self) -> int:
        """Number of basis functions."""
        return self._knots.size - 2

    @property
    def kernel(self):
        """The common kernel, or the tuple of per-interval kernels."""
        return self._kernel if self._kernel is not None else self._kernels

    @property
    def domain(self) -> tuple:
        """(t_1, t_n): where the G_j form a partition of unity."""
        return float(self._knots[1]), float(self._knots[-2])

    @property
    def max_order(self) -> int:
        """Highest derivative order available: the smallest of the kernels' max_order."""
        return min(k.max_order for k in self._kernels)

    def __repr__(self) -> str:
        k = self._knots
        return (f"GERBSBasis(n={self.n}, knots=[{k[0]:g} .. {k[-1]:g}], "
                f"kernel={_kernel_repr(self)})")

    def support(self, j: int) -> tuple:
        """[t_{j-1}, t_{j+1}] for column j (0-based: G_{j+1}), as a tuple."""
        j = check_index("j", j, len(self._knots) - 2)
        return float(self._knots[j]), float(self._knots[j + 2])

    def rising(self, t, nmax: int = 0):
        """The knot interval of each point and the rising B-function there.

        Returns ``(k, rise)`` for the flattened points: ``k`` (P,) int, the knot interval
        (t_k, t_{k+1}] containing t (-1 left of t_0, n + 1 right of t_{n+1}), and
        ``rise`` (nmax+1, P) the derivatives of F_{k+1}(t) = F((t - t_k) / h_k) on it
        (:func:`~gerbs_core.splines.evaluate.rising_jet`; 0 outside [t_0, t_{n+1}]).
        NaN t gives NaN.
        """
        nmax = check_order(nmax, self.max_order, name="nmax", owner="this basis")
        t = as_float_array(t).ravel()
        k = knot_interval(self._knots, t, side="left")
        nan = np.isnan(t)
        k[nan] = 0
        inside = (k >= 0) & (k <= self.n)
        kc = np.clip(k, 0, self.n)
        s = (t - self._knots[kc]) / self._h[kc]
        rise = np.zeros((nmax + 1, t.size))
        for i, ker in enumerate(self._kernels if self._kernel is None else (self._kernel,)):
            sel = inside if self._kernel is not None else inside & (kc == i)
            if sel.any():
                rise[:, sel] = rising_jet(ker, s[sel], self._h[kc[sel]], nmax)
        if nan.any():
            rise[:, nan] = np.nan
        return k, rise

    def active(self, t, nmax: int = 0):
        """The (at most) two basis functions alive at each point, with derivatives.

        Returns ``(k, fall, rise)`` for the flattened points: ``k`` as :meth:`rising`;
        ``fall`` (nmax+1, P) the derivatives of column k-1 (G_k, the falling one) and
        ``rise`` (nmax+1, P) those of column k (G_{k+1}, rising). Entries for
        non-existing columns are 0; NaN t gives NaN.
        """
        k, rise = self.rising(t, nmax)
        fall = falling_jet(rise)
        fall[:, (k < 0) | (k > self.n)] = 0.0
        # G_{n+1} and G_0 do not exist
        rise[:, k == self.n] = 0.0
        fall[:, k == 0] = 0.0
        return k, fall, rise

    def __call__(self, t, nu: int = 0) -> np.ndarray:
        """G_j^(nu)(t) for all j: array (*t.shape, n)."""
        nu = check_order(nu, self.max_order, owner="this basis")
        t = as_float_array(t)
        k, fall, rise = self.active(t, nu)
        P = k.size
        out = np.zeros((P, self.n))
        rows = np.arange(P)
        ok = (k >= 0) & (k <= self.n - 1)
        out[rows[ok], k[ok]] = rise[nu, ok]
        ok = (k >= 1) & (k <= self.n)
        out[rows[ok], k[ok] - 1] = fall[nu, ok]
        nan = np.isnan(t.ravel())
        out[nan] = np.nan
        return out.reshape(t.shape + (self.n,))


class GERBSCurve(Immutable):
    """GERBS curve c(t) = sum_j G_j(t) l_j(t) (eq. (3) basis, local curves l_j).

    Parameters
    ----------
    knots : (n + 2,) strictly increasing (see :class:`GERBSBasis`).
    local_curves : array (n, d) -- constant local curves l_j = P_j (the
        control polygon of Lemma 3); or (n, m + 1, d) -- Taylor (Hermite) data:
        local_curves[j, i] = l_j^(i)(t_j), l_j(t) = sum_i local_curves[j, i]
        (t - t_j)^i / i!, the Taylor polynomial about the knot t_j = knots[j+1].
    kernel : as for GERBSBasis (default ERBS()).

    ``curve(t, nu=0)`` -> (*t.shape, d): c^(nu)(t) by the Leibniz rule
    c^(nu) = sum_j sum_i binom(nu, i) G_j^(i) l_j^(nu - i) (exact given the
    kernel); ``nu`` <= :attr:`max_order`.

    Hermite property: evaluated AT a knot t_j, c^(i)(t_j) is the datum
    local_curves[j, i] (0 for i > m) for every kernel and every i, because the
    kernels report F^(r) = 0 at t = 0 and t = 1 (their value from outside), so only
    l_j contributes there. It is the derivative of the curve (both one-sided limits
    agree with it) when F^(r)(0) = F^(r)(1) = 0 for 1 <= r <= i: all orders for
    ERBS, LogisticStep and Step(at > 0); r <= min(i_left, i_right) for BFBS; none
    for Affine (i = 0 only). Beyond that order c^(i) jumps at t_j and the datum
    returned there is neither one-sided limit (e.g. Affine, i = 1: the datum -0.54
    between the limits -0.66 and 4.4); Step(0) jumps already in value, to the right.
    """

    def __init__(self, knots, local_curves, kernel: Kernel | Sequence[Kernel] | None = None,
                 _nu0: int = 0):
        self._basis = GERBSBasis(knots, kernel)
        L = np.array(local_curves, dtype=np.float64)
        n = self._basis.n
        if L.ndim == 2:
            L = L[:, None, :]
        if L.ndim != 3 or L.shape[0] != n or L.shape[1] < 1 or L.shape[2] < 1:
            raise InvalidParameterError(
                "local_curves", f"expected shape (n, d) or (n, m+1, d) with n = {n} "
                f"(len(knots) - 2), got {np.shape(local_curves)}")
        bad = np.flatnonzero(~np.isfinite(L).all(axis=(1, 2)))
        if bad.size:
            err = InvalidParameterError(
                "local_curves", f"non-finite data for local curves {bad.tolist()[:10]}")
            err.indices = tuple(int(i) for i in bad)
            raise err
        L.setflags(write=False)
        self._L = L
        self._nu0 = int(_nu0)
        self._freeze()

    @property
    def basis(self) -> GERBSBasis:
        return self._basis

    @property
    def knots(self) -> np.ndarray:
        return self._basis.knots

    @property
    def local_curves(self) -> np.ndarray:
        """(n, m + 1, d) Taylor data (constants are stored with m = 0), read-only."""
        return self._L

    @property
    def dim(self) -> int:
        return self._L.shape[2]

    @property
    def max_order(self) -> int:
        """Highest derivative order of this curve: the kernels' max_order, less the orders
        a :meth:`derivative` curve has already taken."""
        return self._basis.max_order - self._nu0

    def _check_nu(self, nu) -> int:
        why = ""
        if self._nu0:
            why = (f"(it is derivative({self._nu0}) of a curve of max_order "
                   f"{self._basis.max_order}: the derivative has used those orders)")
        return check_order(nu, self.max_order, owner="this curve", why=why)

    def __repr__(self) -> str:
        k = self._basis.knots
        d = f", derivative={self._nu0}" if self._nu0 else ""
        return (f"GERBSCurve(n={self._basis.n}, d={self.dim}, m={self._L.shape[1] - 1}, "
                f"knots=[{k[0]:g} .. {k[-1]:g}], "
                f"kernel={_kernel_repr(self._basis)}{d})")

    def derivative(self, nu: int = 1) -> "GERBSCurve":
        """The curve t -> c^(nu)(t), as an object with the same interface."""
        nu = self._check_nu(nu)
        out = GERBSCurve.__new__(GERBSCurve)
        out.__dict__.update(_basis=self._basis, _L=self._L, _nu0=self._nu0 + nu)
        out._freeze()
        return out

    def _local(self, j: np.ndarray, dt: np.ndarray, r: int) -> np.ndarray:
        """l_j^(r)(t) for per-point local curve index j and dt = t - t_j: (P, d)."""
        L = self._L
        m = L.shape[1] - 1
        out = np.zeros((j.size, L.shape[2]))
        # l^(r)(t) = sum_{i >= r} L[j, i] dt^(i-r) / (i-r)!  (Horner from the top)
        for i in range(m, r - 1, -1):
            out *= dt[:, None] / (i - r + 1) if i < m else 1.0
            out += L[j, i]
        return out

    def _local_jet(self, col, centre, t, nu):
        """Jets (nu+1, P, d) of the local curves of columns ``col`` about knots
        ``centre``; 0 where the column does not exist (beyond G_1 and G_n)."""
        n = self._basis.n
        out = np.zeros((nu + 1, t.size, self.dim))
        ok = (col >= 0) & (col <= n - 1)
        if ok.any():
            dt = t[ok] - self._basis.knots[centre[ok]]
            for r in range(nu + 1):
                out[r, ok] = self._local(col[ok], dt, r)
        return out

    def __call__(self, t, nu: int = 0) -> np.ndarray:
        """c^(nu)(t): array (*t.shape, d)."""
        nu = self._check_nu(nu) + self._nu0
        t = as_float_array(t)
        k, rise = self._basis.rising(t, nu)
        tf = t.ravel()
        # falling G_k (column k-1, centred at t_k); rising G_{k+1} (column k, at t_{k+1})
        left = self._local_jet(k - 1, k, tf, nu)
        right = self._local_jet(k, k + 1, tf, nu)
        out = blend_jet(left, right, rise[..., None], nu)[nu]
        out[np.isnan(tf)] = np.nan
        return out.reshape(t.shape + (self.dim,))
