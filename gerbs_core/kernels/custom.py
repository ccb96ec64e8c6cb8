"""A user-supplied CDF as a GERBS kernel (paper Definition 2)."""
from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import InvalidParameterError
from .base import Kernel

__all__ = ["CustomCDF"]

_TOL = 1e-12


def _call(fn, x, name):
    try:
        v = np.asarray(fn(x), dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(name, f"calling it on an array failed: {exc}") from exc
    if v.shape != x.shape:
        raise InvalidParameterError(
            name, f"must be vectorized: returned shape {v.shape} for input shape {x.shape}")
    return v


class CustomCDF(Kernel):
    """Kernel from any CDF f on [0, 1] (Definition 2) and optional derivatives.

    Parameters
    ----------
    f : callable, vectorized: f(x) has the shape of x; called only on (0, 1)
        after validation (F = 0 for t <= 0 and 1 for t >= 1 by definition).
    derivatives : sequence of callables [f', f'', ...] (vectorized), optional.
        ``max_order`` = len(derivatives) (0 without them).
    smoothness : declared m with F in C^m (default: -1 if nothing is known,
        i.e. no smoothness is assumed).
    n_check : size of the validation grid on [0, 1].

    Validation (on ``n_check`` equispaced points of [0, 1], tolerance 1e-12):
    finite values, f(0) = 0, f(1) = 1, monotone non-decreasing. Failures
    raise InvalidParameterError("f", ...) stating where.
    """

    def __init__(self, f, derivatives=None, smoothness=None, n_check: int = 4097):
        if not callable(f):
            raise InvalidParameterError("f", f"must be callable, got {type(f).__name__}")
        derivatives = tuple(derivatives) if derivatives is not None else ()
        for k, d in enumerate(derivatives):
            if not callable(d):
                raise InvalidParameterError(
                    "derivatives", f"entry {k} (order {k + 1}) is not callable")
        if isinstance(n_check, bool) or not isinstance(n_check, numbers.Integral) or n_check < 3:
            raise InvalidParameterError("n_check", f"must be an integer >= 3, got {n_check!r}")
        x = np.linspace(0.0, 1.0, int(n_check))
        v = _call(f, x, "f")
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise InvalidParameterError("f", f"non-finite value at t = {x[bad[0]]!r}")
        if abs(v[0]) > _TOL:
            raise InvalidParameterError("f", f"a CDF must have F(0) = 0, got {v[0]!r}")
        if abs(v[-1] - 1.0) > _TOL:
            raise InvalidParameterError("f", f"a CDF must have F(1) = 1, got {v[-1]!r}")
        dec = np.flatnonzero(np.diff(v) < -_TOL)
        if dec.size:
            k = dec[0]
            raise InvalidParameterError(
                "f", f"not monotone: F decreases between t = {x[k]!r} and t = {x[k + 1]!r}"
                f" ({dec.size} decreasing steps on the check grid)")
        for k, d in enumerate(derivatives):
            dv = _call(d, x[1:-1], "derivatives")
            if not np.all(np.isfinite(dv)):
                raise InvalidParameterError(
                    "derivatives", f"entry {k} (order {k + 1}) has non-finite values in (0, 1)")
        if smoothness is None:
            smoothness = -1
        elif not (smoothness == math.inf or (isinstance(smoothness, numbers.Integral)
                                             and smoothness >= -1)):
            raise InvalidParameterError(
                "smoothness", f"must be an integer >= -1 or math.inf, got {smoothness!r}")
        s = object.__setattr__
        s(self, "f", f)
        s(self, "derivatives", derivatives)
        s(self, "max_order", len(derivatives))
        s(self, "smoothness", smoothness)

    def _params(self):
        return (self.f, self.derivatives)

    def __repr__(self):
        return f"CustomCDF({self.f!r}, {self.derivatives!r}, smoothness={self.smoothness!r})"

    def _interior(self, x, nmax):
        out = np.empty((nmax + 1, x.size))
        out[0] = _call(self.f, x, "f")
        for k in range(1, nmax + 1):
            out[k] = _call(self.derivatives[k - 1], x, "derivatives")
        return out
