"""Expo-rational B-spline kernel (ERBS), paper eqs. (1)-(2), DESIGN section 1.

On [0, 1] (the knot interval [t_k, t_{k+1}] after the affine change of
variable) the ERBS density of eq. (2) is, up to normalization,

    phi(t) = exp(E(t)),  E(t) = -beta |t - lam|^(2 sigma) / (t (1 - t)^gamma)^alpha,

for 0 < t < 1 (gamma acts on the right factor only, as eq. (2) is typeset),
and F(t) = int_0^t phi / Z with Z = int_0^1 phi. Defaults alpha = beta =
gamma = sigma = 1, lam = 1/2, for which E(t) = 1 - 1 / (4 t (1 - t)).

What is exact and what is approximate:

* Z and the table for F are computed once per parameter set (and cached) by
  adaptive Clenshaw-Curtis quadrature (:class:`~._table.ChebyshevMaster`:
  bisection until the degree-24 Chebyshev interpolant of phi on every cell has
  an integrated tail below 1e-18). Values F(t) then come from low-degree
  piecewise polynomials interpolating that integral at Chebyshev nodes,
  checked at build time against the master to 5e-15 (uniform cells when
  that suffices: index floor(t M), no search; evaluation in cache-sized
  chunks, which is what makes it as cheap as one elementary step s(t) in
  numpy -- scripts/bench_kernels.py); measured |F - F_ref|
  against an independent scipy.integrate.quad reference is ~1e-15
  (tests/core/test_kernels_erbs.py).
* Derivatives F^(k), k >= 1, are F^(k) = phi^(k-1) / Z with phi^(k-1)
  computed in closed form: the Taylor coefficients of E are exact algebraic
  expressions (for alpha = gamma = sigma = 1, E = beta - beta lam^2 / t -
  beta (1 - lam)^2 / (1 - t), a sum of two poles), and exp(E) is expanded by
  the exact recurrence w' = E' w (one exp per point for all orders). Only
  rounding and the quadrature error of Z (relative ~1e-16) enter.

Smoothness (derived from eq. (2)): with p = 2 sigma, |t - lam|^p is C^inf if
p is an even integer (or 0), C^(p-1) if p is odd, C^floor(p) otherwise; so F
is C^inf, C^p, C^(floor(p)+1) respectively at an interior lam -- i.e.
C^ceil(p) when p is not an even integer. At the ends F is flat (every
derivative vanishes) unless lam = 0 and p >= alpha (then phi(0+) > 0, F' jumps
at 0: C^0), or lam = 1 and p >= alpha * gamma (same at 1).
"""
from __future__ import annotations

import math
import numbers
from functools import lru_cache

import numpy as np

from ..errors import InvalidParameterError
from . import erbs_store
from ._series import exp_series
from ._table import CHUNK
from .base import Kernel, check_order
from .erbs_table import UNDERFLOW, build_tables

__all__ = ["ERBS"]



def binom(n: float, k: int) -> float:
    """Generalized binomial coefficient n (n-1) ... (n-k+1) / k! (any real n)."""
    out = 1.0
    for i in range(k):
        out *= (n - i) / (i + 1)
    return out


def _real(name, value):
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise InvalidParameterError(name, f"must be a real number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InvalidParameterError(name, f"must be finite, got {value}")
    return value


class ERBS(Kernel):
    """ERBS kernel F(t) = int_0^t phi / int_0^1 phi, phi from eq. (2).

    Parameters
    ----------
    alpha, beta, gamma : float > 0
    lam : float in [0, 1] (position of the density's maximum for sigma > 0)
    sigma : float >= 0

    Raises InvalidParameterError naming the parameter when out of range, and
    (at construction) when the parameter set cannot be tabulated in double
    precision: the density is then concentrated on an interval too short to
    resolve (F is numerically a step) -- see docs/robustness.md for the box
    of parameters that is guaranteed to work.
    ``max_order`` = 8. ``Z`` is the normalizing integral of eq. (2), of the
    density scaled by exp(-max E) (``log_scale``): eq. (2)'s own Z underflows to
    0 for e.g. sigma = 0, alpha = 8 (max E = -4^alpha beta), F does not change.
    """

    max_order = 8

    def __init__(self, alpha=1.0, beta=1.0, gamma=1.0, lam=0.5, sigma=1.0, *, _check=True):
        alpha, beta, gamma = _real("alpha", alpha), _real("beta", beta), _real("gamma", gamma)
        lam, sigma = _real("lam", lam), _real("sigma", sigma)
        for name, v in (("alpha", alpha), ("beta", beta), ("gamma", gamma)):
            if v <= 0.0:
                raise InvalidParameterError(name, f"must be > 0, got {v}")
        if not 0.0 <= lam <= 1.0:
            raise InvalidParameterError("lam", f"must lie in [0, 1], got {lam}")
        if sigma < 0.0:
            raise InvalidParameterError("sigma", f"must be >= 0, got {sigma}")
        s = object.__setattr__
        s(self, "alpha", alpha)
        s(self, "beta", beta)
        s(self, "gamma", gamma)
        s(self, "lam", lam)
        s(self, "sigma", sigma)
        p = 2.0 * sigma
        s(self, "_p", p)
        # E = beta - beta lam^2/t - beta (1-lam)^2/(1-t)  (partial fractions)
        s(self, "_rational", alpha == 1.0 and gamma == 1.0 and sigma == 1.0)
        s(self, "smoothness", self._smoothness())
        if _check:
            _tables(self)  # build (cached) and validate now: bad sets fail at construction

    def _params(self):
        return (self.alpha, self.beta, self.gamma, self.lam, self.sigma)

    def __repr__(self):
        return ("ERBS(alpha={!r}, beta={!r}, gamma={!r}, lam={!r}, sigma={!r})"
                .format(*self._params()))

    def _smoothness(self):
        p, a, c = self._p, self.alpha, self.alpha * self.gamma
        m = math.inf
        if 0.0 < self.lam < 1.0 and p != 0.0 and not (p == int(p) and int(p) % 2 == 0):
            m = math.ceil(p)
        if (self.lam == 0.0 and p >= a) or (self.lam == 1.0 and p >= c):
            m = 0
        return m

    # -- the density ------------------------------------------------------
    def log_density_series(self, x: np.ndarray, n: int) -> list:
        """Taylor coefficients E_0..E_n of E at points x in (0, 1) (E_k = E^(k)/k!).

        Exact closed forms; at x = lam with p = 2 sigma not an even integer the
        coefficients of order > p are infinite (phi is not smooth there).
        """
        beta, lam = self.beta, self.lam
        if self._rational:
            a = 1.0 / x
            b = 1.0 / (1.0 - x)
            l2, r2 = beta * lam * lam, beta * (1.0 - lam) ** 2
            E = [beta - l2 * a - r2 * b]
            ak, bk = a, b
            for k in range(1, n + 1):
                ak = ak * a
                bk = bk * b
                E.append((l2 * ak if k % 2 else -l2 * ak) - r2 * bk)
            return E
        p, al, c = self._p, self.alpha, self.alpha * self.gamma
        d = x - lam
        ad = np.abs(d)
        P = []
        for k in range(n + 1):
            bk = binom(p, k)
            if bk == 0.0:
                P.append(np.zeros_like(x))
            else:
                with np.errstate(divide="ignore", invalid="ignore"):
                    term = bk * ad ** (p - k)
                P.append(term * np.sign(d) ** k if k % 2 else term)
        A = [binom(-al, k) * x ** (-al - k) for k in range(n + 1)]
        omx = 1.0 - x
        B = [binom(c + k - 1.0, k) * omx ** (-c - k) for k in range(n + 1)]
        E = []
        for k in range(n + 1):
            acc = 0.0
            for i in range(k + 1):
                AB = sum(A[j] * B[k - i - j] for j in range(k - i + 1))
                acc = acc + P[i] * AB
            E.append(-beta * acc)
        return E

    def density(self, t, nu: int = 0):
        """phi^(nu)(t) / Z = F^(nu+1)(t), the normalized density of eq. (2)."""
        nu = check_order(nu, self.max_order - 1)
        return self.cdf(t, nu + 1)

    @property
    def Z(self) -> float:
        """The normalizing integral int_0^1 phi exp(-log_scale) (adaptive quadrature)."""
        return _tables(self)[0].Z

    @property
    def log_scale(self) -> float:
        """max of E on a fine grid of (0, 1): the density is tabulated as exp(E - log_scale)."""
        return _tables(self)[3]

    # -- evaluation -------------------------------------------------------
    def _eval_one(self, t, nu):
        if nu == 0:
            return _tables(self)[1](t)
        return np.asarray(self._eval(t, nu)[nu])

    def _eval(self, t, nmax):
        master, table, clip, shift = _tables(self)
        out = np.empty((nmax + 1,) + t.shape)
        if nmax == 0:
            table(t.reshape(-1), out=out.reshape(-1))      # (also right for 0-d t)
            return out
        if clip is None:                  # phi not flat at an end: masked path
            out[0] = table(t)
            out[1:] = Kernel._eval(self, t, nmax)[1:]
            return out
        # phi == 0.0 exactly outside [lo, hi]: clipping there gives exact zeros
        # for every derivative without masks (NaN stays NaN). Cache-sized chunks.
        flat = t.reshape(-1)
        res = out.reshape(nmax + 1, -1)
        inv_z = 1.0 / master.Z
        for s in range(0, flat.size, CHUNK):
            tc = flat[s:s + CHUNK]
            table._chunk(tc, res[0, s:s + CHUNK])
            x = np.minimum(tc, clip[1])
            np.maximum(x, clip[0], out=x)
            self._derivs_into(x, nmax, res[1:, s:s + CHUNK], inv_z, shift)
        return out

    def _derivs_into(self, x, nmax, dst, inv_z, shift):
        """dst[k-1] = F^(k)(x) = (k-1)! w_{k-1} / Z for k = 1..nmax (w = exp(E - shift)
        series; the constant shift only rescales the density, Z is computed with it)."""
        E = self.log_density_series(x, nmax - 1)
        E[0] = E[0] - shift
        w0 = np.exp(E[0], out=dst[0])
        w0 *= inv_z
        w = exp_series(E, w0)
        for k in range(2, nmax + 1):
            np.multiply(w[k - 1], float(math.factorial(k - 1)), out=dst[k - 1])

    def _interior(self, x, nmax):
        master, table, _, shift = _tables(self)
        out = np.zeros((nmax + 1, x.size))
        out[0] = table(x)
        with np.errstate(all="ignore"):
            E0 = self.log_density_series(x, 0)[0] - shift
        live = E0 > UNDERFLOW
        if live.any():
            sub = np.empty((nmax, int(live.sum())))
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                self._derivs_into(x[live], nmax, sub, 1.0 / master.Z, shift)
            out[1:, live] = sub
        return out


def _tables(k: ERBS):
    """(master, fast table, clip interval or None, log scale) of k's parameter set."""
    params = k._params()
    return _default_tables() if params == erbs_store.DEFAULT else build_tables(ERBS, params)


@lru_cache(maxsize=1)
def _default_tables():
    """ERBS()'s tables: stored with the package (:mod:`.erbs_store`), else built."""
    return erbs_store.load() or build_tables(ERBS, erbs_store.DEFAULT)
