"""The two ends of the GERBS hierarchy (paper section 2.1.3): Affine and Step.

* :class:`Affine`: F(t) = t on [0, 1] -- the GERBS of eq. (3) are then the
  piecewise affine hat B-splines. C^0: F' jumps from 0 to 1 at t = 0 and
  from 1 to 0 at t = 1.
* :class:`Step`: a discontinuous, left-continuous CDF (Definition 2, item 4):
  F(t) = 0 for t <= at, F(t) = 1 for t > at. With the default ``at = 1/2`` the
  GERBS G_j of eq. (3) is the indicator of (m_{j-1}, m_j] between the knot
  midpoints m_j = (t_j + t_{j+1}) / 2 ("nearest knot" piecewise constants),
  which still interpolates: G_j(t_k) = delta_jk. With ``at = 0``, G_j is the
  indicator of (t_{j-1}, t_j], the classical left-continuous piecewise constant
  B-spline (then F(0+) = 1, i.e. item 1 of Definition 2 is relaxed).
"""
from __future__ import annotations

import numbers

import numpy as np

from ..errors import InvalidParameterError
from .base import Kernel

__all__ = ["Affine", "Step"]


class Affine(Kernel):
    """F(t) = t on [0, 1] (exact). F' = 1 inside (0, 1), higher derivatives 0.

    C^0 on R (smoothness = 0). As everywhere, derivatives at t = 0 and t = 1
    are reported as 0 (the value from outside).
    """

    max_order = 8
    smoothness = 0

    def __init__(self):
        pass

    def _eval(self, t, nmax):
        flat = t.reshape(-1)
        out = np.zeros((nmax + 1, flat.size))
        np.clip(flat, 0.0, 1.0, out=out[0])       # NaN propagates through clip
        if nmax >= 1:
            with np.errstate(invalid="ignore"):
                out[1] = (flat > 0.0) & (flat < 1.0)
            out[1:, np.isnan(flat)] = np.nan
        return out.reshape((nmax + 1,) + t.shape)


class Step(Kernel):
    """Left-continuous step F(t) = 0 for t <= at, 1 for t > at (exact).

    Parameters
    ----------
    at : float, 0 <= at < 1 (default 0.5). Position of the jump.

    Discontinuous (smoothness = -1). Derivatives of order >= 1 are 0 wherever
    they exist (everywhere except t = at, where 0 is reported too).
    """

    max_order = 8
    smoothness = -1

    def __init__(self, at: float = 0.5):
        if isinstance(at, bool) or not isinstance(at, numbers.Real) or not np.isfinite(at):
            raise InvalidParameterError("at", f"must be a finite real number, got {at!r}")
        if not 0.0 <= at < 1.0:
            raise InvalidParameterError("at", f"jump position must satisfy 0 <= at < 1, got {at}")
        object.__setattr__(self, "at", float(at))

    def _params(self):
        return (self.at,)

    def _eval(self, t, nmax):
        flat = t.reshape(-1)
        out = np.zeros((nmax + 1, flat.size))
        out[0] = flat > self.at
        out[:, np.isnan(flat)] = np.nan
        return out.reshape((nmax + 1,) + t.shape)
