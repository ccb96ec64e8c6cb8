"""The tabulation of an ERBS kernel: normalising integral, value table, clip interval.

Built once per parameter set (cached) when an :class:`~gerbs_core.kernels.erbs.ERBS`
is constructed: Z = int_0^1 phi by adaptive Clenshaw-Curtis quadrature
(:class:`~._table.ChebyshevMaster`), the fast value pieces of degree 4 checked
against it to 5e-15, the density's log scale (so exp(E - scale) neither overflows nor
underflows everywhere), and the interval outside which the density is exactly 0.0 in
double precision. A parameter set that cannot be tabulated raises
InvalidParameterError naming the parameter farthest from its default.
"""
from __future__ import annotations

import math
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InvalidParameterError
from ._table import ChebyshevMaster, PiecewisePoly, fit_pieces

if TYPE_CHECKING:
    from .erbs import ERBS

__all__ = ["build_tables", "UNDERFLOW"]

_DEG = 4                 # degree of the fast value pieces
_TABLE_TOL = 5e-15       # accepted |table - master| at the build-time check
UNDERFLOW = -800.0       # E below this: exp(E) == 0.0 in double precision


def _log_scale(kern: ERBS) -> float:
    """max E over (0, 1), located on a graded grid (dense near the ends and lam) and
    polished by zooming grids around the best point (4 rounds of 65 points, each 32x
    narrower: a vectorized search; scipy.optimize's import alone cost a third of a
    first call): exp(E - max E) <= ~1 never overflows and does not underflow
    everywhere (which eq. (2) unscaled does, e.g. sigma = 0, alpha = 8: E <= -4^8).
    Only a scale: F does not depend on it beyond rounding."""
    u = np.linspace(0.0, 1.0, 4097)[1:-1]
    near_lam = np.clip(kern.lam + (u - 0.5) ** 3, 1e-300, 1.0 - 1e-16)
    x = np.unique(np.concatenate([u, u ** 4, 1.0 - u ** 4, near_lam]))
    x = x[(x > 0.0) & (x < 1.0)]

    def energy(t):
        with np.errstate(all="ignore"):
            E = kern.log_density_series(t, 0)[0]
        return np.where(np.isnan(E), -np.inf, E)

    E = energy(x)
    k = int(np.argmax(E))
    best = float(E[k])
    if not np.isfinite(best):
        return 0.0
    a, b = x[max(k - 1, 0)], x[min(k + 1, len(x) - 1)]
    for _ in range(4):
        if not b > a:
            break
        t = np.linspace(a, b, 65)
        Et = energy(t)
        j = int(np.argmax(Et))
        best = max(best, float(Et[j]))
        a, b = t[max(j - 1, 0)], t[min(j + 1, 64)]
    return best


def _name_extreme(kern: ERBS) -> str:
    """The parameter farthest from its default (log scale for alpha, beta, gamma, sigma)."""
    d = {n: abs(math.log(v)) for n, v in (("alpha", kern.alpha), ("beta", kern.beta),
                                           ("gamma", kern.gamma))}
    d["sigma"] = abs(math.log(kern.sigma)) if kern.sigma > 0 else 0.0
    d["lam"] = 2.0 * abs(kern.lam - 0.5)
    return max(d, key=d.get)


_MASTER_TOL = 1e-11      # accepted estimated quadrature error of the master, relative to Z
_MASTER_CAP = 1e-7       # ... or up to the noise of exp(E - max E) (|max E| eps), but never more


def _noise(shift: float) -> float:
    """Relative rounding noise of exp(E - shift): E ~ shift is computed to ~|shift| eps."""
    return 16.0 * np.finfo(float).eps * abs(shift)


def _refuse(kern: ERBS, problem: str):
    return InvalidParameterError(
        _name_extreme(kern),
        f"ERBS(alpha={kern.alpha}, beta={kern.beta}, gamma={kern.gamma}, lam={kern.lam}, "
        f"sigma={kern.sigma}) cannot be tabulated: {problem}; F is numerically a step "
        f"(see docs/robustness.md for the guaranteed parameter box)")


def _tolerance(shift: float) -> float:
    """Accepted relative error of Z and of the table: 1e-11, or the noise of
    exp(E - shift) if larger, never more than 1e-7."""
    return min(max(_MASTER_TOL, 4.0 * _noise(shift)), _MASTER_CAP)


@lru_cache(maxsize=64)
def build_tables(kernel_class, params):
    """(master, fast table, clip interval or None, log scale) for one parameter set.

    Raises InvalidParameterError (not cached) if the set cannot be tabulated."""
    kern = kernel_class(*params, _check=False)
    lam = kern.lam
    shift = _log_scale(kern)

    def phi(x):
        with np.errstate(all="ignore"):
            E0 = kern.log_density_series(x, 0)[0] - shift
            v = np.exp(E0)
        v[~np.isfinite(v)] = 0.0
        return v

    try:
        master = ChebyshevMaster(phi, breaks=(lam,), noise=_noise(shift))
    except RuntimeError:  # could not resolve the density within max_cells
        raise _refuse(kern, "the density could not be resolved by adaptive quadrature") from None
    tol = _tolerance(shift)
    if not (np.isfinite(master.Z) and master.Z > 0.0):
        raise _refuse(kern, f"the density integrates to {master.Z!r} in double precision")
    if not master.tail_sum <= tol * master.Z:
        raise _refuse(kern, f"the density is too concentrated to resolve (relative quadrature "
                            f"error estimate {master.tail_sum / master.Z:.1e})")
    table, table_err = _fit_table(master, lam, kern.smoothness)
    if not table_err <= max(tol, 1e-12):
        raise _refuse(kern, f"the value table misses the quadrature by {table_err:.1e}")
    clip = _clip_interval(kern, shift)
    return master, table, clip, shift


def _fit_table(master: ChebyshevMaster, lam: float, smoothness):
    """(fast value table, its measured max error): uniform pieces if they reach
    _TABLE_TOL, else graded."""
    offs = np.array([0.11, 0.29, 0.5, 0.71, 0.89])

    def err(breaks, coef):
        pp = PiecewisePoly(breaks, coef, uniform=False)
        a, h = breaks[:-1], np.diff(breaks)
        x = (a[:, None] + h[:, None] * offs).ravel()
        return float(np.abs(pp(x) - master(x)).max())

    for M in (256, 512, 1024, 2048, 4096, 8192):
        breaks = np.linspace(0.0, 1.0, M + 1)
        coef = fit_pieces(master, breaks, _DEG)
        e = err(breaks, coef)
        if e <= _TABLE_TOL:
            return PiecewisePoly(breaks, coef, uniform=True), e
    # graded: split every master cell (graded towards lam and the ends)
    for parts in (4, 8, 16, 32, 64):      # the finest is kept whatever its error
        breaks = np.unique(np.concatenate(
            [master.a[:, None] + np.diff(master.breaks)[:, None] * np.arange(parts) / parts,
             ]).ravel())
        breaks = np.concatenate([breaks, [1.0]])
        coef = fit_pieces(master, breaks, _DEG)
        e = err(breaks, coef)
        if e <= _TABLE_TOL:
            break
    return PiecewisePoly(breaks, coef, uniform=False), e


def _clip_interval(kern: ERBS, shift: float):
    """[lo, hi] outside which exp(E - shift) == 0.0 and E's series stays finite, else None."""
    n = kern.max_order - 1

    def E0(x):
        with np.errstate(all="ignore"):
            return float(kern.log_density_series(np.array([x]), 0)[0][0]) - shift

    def edge(inside, outside):
        # bisection between a point where phi > 0 and one where it underflows. Any point
        # where it underflows clips correctly (exp(E) == 0.0 up to the threshold), so
        # closeness only saves work; 64 halvings reach one ulp at thresholds >= ~1e-4
        if not E0(outside) <= UNDERFLOW:
            return None
        lo, hi = outside, inside
        for _ in range(64):
            mid = 0.5 * (lo + hi)
            if E0(mid) <= UNDERFLOW:
                lo = mid
            else:
                hi = mid
        return lo

    lo = edge(kern.lam if kern.lam > 0 else 0.5, 1e-30)
    hi = edge(kern.lam if kern.lam < 1 else 0.5, 1.0 - 1e-15)
    if lo is None or hi is None:
        return None
    with np.errstate(all="ignore"):
        E = kern.log_density_series(np.array([lo, hi]), n)
    if not all(np.all(np.isfinite(e)) for e in E):
        return None
    return lo, hi
