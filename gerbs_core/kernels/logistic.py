"""The elementary C-infinity GERBS kernel F(t) = 1 / (1 + exp(1/t - 1/(1-t))).

Paper section 2.1.2 asks for smooth GERBS densities that integrate in
elementary functions; this is one: F is in closed form, C-infinity on R, and
every derivative vanishes at 0 and 1 (F(t) ~ exp(-1/t) as t -> 0+).
Symmetric: F(1 - t) = 1 - F(t).
"""
from __future__ import annotations

import math

import numpy as np

from ._series import logistic_series, to_derivatives
from .base import Kernel

__all__ = ["LogisticStep"]

# below this distance from 0 (or 1) exp(-1/t) underflows: F = 0 (or 1) and every
# derivative is < 1e-290 in absolute value, i.e. 0 to double precision.
_EDGE = 1.0 / 700.0


class LogisticStep(Kernel):
    """F(t) = 1 / (1 + exp(g(t))), g(t) = 1/t - 1/(1-t) = (1 - 2t) / (t (1 - t)).

    Exact closed form for the value; derivatives 1..max_order exact (to
    rounding) from the closed-form derivatives of g,
    g^(k)(t) = (-1)^k k! / t^(k+1) - k! / (1-t)^(k+1),
    pushed through the logistic ODE F' = -g' F (1 - F) in Taylor arithmetic.
    C-infinity; all derivatives vanish at 0 and 1.
    """

    max_order = 8
    smoothness = math.inf

    def __init__(self):
        pass

    def _eval_one(self, t, nu):
        if nu == 0:
            return self._values(t)
        return Kernel._eval_one(self, t, nu)

    @staticmethod
    def _values(t):
        # (1 - 2t) / (t - t^2) keeps relative accuracy of g near t = 1/2;
        # clip so that out-of-range t gives 0 / 1 without special cases.
        x = np.clip(t, 0.0, 1.0)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            g = (1.0 - 2.0 * x) / (x - x * x)
            # x = 0: g = 1/0 = +inf -> F = 0; x = 1: g = -1/0 = -inf -> F = 1 (exact)
            return np.asarray(1.0 / (1.0 + np.exp(g)))

    def _interior(self, x, nmax):
        out = np.zeros((nmax + 1, x.size))
        F0 = self._values(x)
        out[0] = F0
        if nmax == 0:
            return out
        live = (x > _EDGE) & (x < 1.0 - _EDGE)
        x = x[live]
        a = 1.0 / x
        b = 1.0 / (1.0 - x)
        g = [a - b]
        ak, bk = a, b
        for k in range(1, nmax + 1):
            ak = ak * a
            bk = bk * b
            g.append((-ak if k % 2 else ak) - bk)  # g^(k)/k!
        with np.errstate(over="ignore"):
            G0 = 1.0 / (1.0 + np.exp(-g[0]))
        series = logistic_series(g, F0[live], G0)
        out[1:, live] = to_derivatives(series)[1:]
        return out
