"""The :class:`Kernel` base class: a CDF ``F`` on [0, 1] (paper, Definition 2).

A kernel is a cumulative distribution function F with F = 0 on (-inf, 0],
F = 1 on [1, +inf), monotone in between. It generates

* the GERBS "rising" part ``F`` (eq. (3), first case, after the affine change
  of variable t -> (t - t_{j-1}) / (t_j - t_{j-1})), and
* the GERBS "peaking at 0" ``b(t) = 1 - F(|t|)`` for |t| < 1, 0 elsewhere
  (supp b = [-1, 1]; DESIGN section 1).

Conventions shared by every kernel (DESIGN section 1):

* ``t`` may be any array shape (or a scalar); the result has the same shape
  (scalars give a 0-d ``numpy.float64``). Input is converted to float64; the
  caller's array is never modified.
* Out-of-range input is clamped by definition: F = 0 for t <= 0, F = 1 for
  t >= 1, and every derivative F^(nu), nu >= 1, is reported as 0 outside the
  open interval (0, 1) -- including at t = 0 and t = 1 themselves. For the
  smooth kernels (ERBS, LogisticStep) this is the true value; for kernels that
  are only C^m at the knots it is the one-sided value from outside.
* NaN in gives NaN out (for every derivative order).
* ``nu`` must be an integer with 0 <= nu <= ``max_order``, otherwise
  :class:`~gerbs_core.errors.InvalidParameterError` naming ``nu``.

Subclasses implement :meth:`Kernel._interior` (derivatives 0..nmax at points
strictly inside (0, 1)); the base class handles clamping, NaN and shapes.
Subclasses with a faster whole-array path override :meth:`Kernel._eval`.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import InvalidParameterError

__all__ = ["Kernel", "as_float_array", "check_order"]


def as_float_array(t, name: str = "t") -> np.ndarray:
    """``t`` as a float64 ndarray (a new array only if a conversion is needed).

    Raises InvalidParameterError(name) for complex, object or non-numeric input.
    """
    arr = np.asarray(t)
    if arr.dtype.kind not in "biuf":
        raise InvalidParameterError(
            name, f"expected real numbers, got an array of dtype {arr.dtype}")
    return arr.astype(np.float64, copy=False)


def check_order(nu, max_order: int, name: str = "nu", owner: str = "this kernel",
                why: str = "") -> int:
    """Validate a derivative order: an int (Python or numpy, not a bool, not a float even
    if whole) with 0 <= nu <= max_order; the one check of every ``nu`` of the package
    (kernels, curves, surfaces, interpolators, gauges; `owner` names whose maximum, `why`
    (optional) says where that maximum comes from, e.g. "(its kernel has max_order 0)")."""
    if isinstance(nu, (bool, np.bool_)) or not isinstance(nu, numbers.Integral):
        raise InvalidParameterError(name, f"derivative order must be an integer, got {nu!r}")
    nu = int(nu)
    if nu < 0:
        raise InvalidParameterError(name, f"derivative order must be >= 0, got {nu}")
    if nu > max_order:
        raise InvalidParameterError(
            name, f"derivative order {nu} exceeds {owner}'s max_order = {max_order}"
            + (f" {why}" if why else ""))
    return nu


class Kernel:
    """Abstract GERBS kernel: a CDF F on [0, 1] and the bump b(t) = 1 - F(|t|).

    Attributes
    ----------
    max_order : int
        Highest derivative order available from :meth:`cdf` / :meth:`cdf_derivs`.
    smoothness : int or float
        m such that F is C^m on the whole real line (``math.inf`` for
        C-infinity, -1 for a discontinuous F).

    Kernels are immutable value objects: equal parameters compare equal and
    hash equal, and attributes cannot be reassigned.
    """

    max_order: int = 8
    smoothness: float = math.inf
    __slots__ = ()

    # -- immutability -------------------------------------------------------
    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __delattr__(self, name):
        raise AttributeError(f"{type(self).__name__} is immutable")

    def _params(self) -> tuple:
        """Parameters identifying the kernel (for ==, hash and repr)."""
        return ()

    def __eq__(self, other):
        return type(self) is type(other) and self._params() == other._params()

    def __hash__(self):
        return hash((type(self).__name__, self._params()))

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(repr(p) for p in self._params())})"

    # -- public evaluation --------------------------------------------------
    def cdf(self, t, nu: int = 0):
        """F^(nu)(t), the nu-th derivative of the CDF; same shape as ``t``.

        Parameters
        ----------
        t : array_like, any shape
        nu : int, 0 <= nu <= max_order
        """
        nu = check_order(nu, self.max_order)
        t = as_float_array(t)
        out = self._eval_one(t, nu)
        return out[()] if out.ndim == 0 else out

    def cdf_derivs(self, t, nmax: int):
        """F, F', ..., F^(nmax) at once; array of shape (nmax + 1, *t.shape).

        Shares the expensive work (one exponential for ERBS / LogisticStep)
        between the orders; meant for hot loops.
        """
        nmax = check_order(nmax, self.max_order, name="nmax")
        t = as_float_array(t)
        return self._eval(t, nmax)

    def bump(self, t, nu: int = 0):
        """b^(nu)(t) for b(t) = 1 - F(|t|) (|t| < 1), 0 elsewhere; shape of ``t``.

        For nu >= 1, b^(nu)(t) = -sign(t)^nu F^(nu)(|t|); at t = 0 this is 0
        (exact for kernels flat at 0, e.g. ERBS; a convention otherwise).
        """
        nu = check_order(nu, self.max_order)
        t = as_float_array(t)
        out = _bump_from_cdf(t, self._eval_one(np.abs(t), nu), nu)
        return out[()] if out.ndim == 0 else out

    def bump_derivs(self, t, nmax: int):
        """b, b', ..., b^(nmax) at once; array of shape (nmax + 1, *t.shape)."""
        nmax = check_order(nmax, self.max_order, name="nmax")
        t = as_float_array(t)
        d = self._eval(np.abs(t), nmax)
        for k in range(nmax + 1):
            d[k] = _bump_from_cdf(t, d[k], k)
        return d

    def __call__(self, t, nu: int = 0):
        """Alias of :meth:`cdf` (scipy-style ``obj(x, nu=k)``)."""
        return self.cdf(t, nu)

    # -- hooks for subclasses -------------------------------------------------
    def _eval_one(self, t: np.ndarray, nu: int) -> np.ndarray:
        """F^(nu) on a float64 array (any shape); default: via :meth:`_eval`."""
        return np.asarray(self._eval(t, nu)[nu])

    def _eval(self, t: np.ndarray, nmax: int) -> np.ndarray:
        """Derivatives 0..nmax on a float64 array: clamp, NaN, then _interior."""
        flat = t.reshape(-1)
        out = np.zeros((nmax + 1, flat.size))
        with np.errstate(invalid="ignore"):
            inner = (flat > 0.0) & (flat < 1.0)
            out[0][flat >= 1.0] = 1.0
        nan = np.isnan(flat)
        if nan.any():
            out[:, nan] = np.nan
        if inner.any():
            out[:, inner] = self._interior(flat[inner], nmax)
        return out.reshape((nmax + 1,) + t.shape)

    def _interior(self, x: np.ndarray, nmax: int) -> np.ndarray:
        """Derivatives 0..nmax at 1-d points strictly inside (0, 1): (nmax+1, len(x))."""
        raise NotImplementedError


def _bump_from_cdf(t: np.ndarray, dF: np.ndarray, nu: int) -> np.ndarray:
    """b^(nu)(t) from F^(nu)(|t|): 1 - F for nu = 0, -sign(t)^nu F^(nu) else."""
    if nu == 0:
        return 1.0 - dF
    if nu % 2 == 0:
        return np.where(t == 0.0, 0.0, -dF)
    return -np.sign(t) * dF
