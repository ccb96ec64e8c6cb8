"""Euler Beta-function B-spline kernel (BFBS), paper Definition 4, eqs. (4)-(7).

Mapping from the paper. In eq. (6) the density on the knot interval
[t_k, t_{k+1}] is psi_k(t) = C_k (t - t_k)^{i_k} (t_{k+1} - t)^{i_{k+1}} /
(t_{k+1} - t_k)^{i_k + i_{k+1}}; after the change of variable
t -> (t - t_k) / (t_{k+1} - t_k) it is proportional to t^{i_k} (1 - t)^{i_{k+1}}
on [0, 1]. S_k of eq. (5) normalizes it (C_k = binom(i_k + i_{k+1}, i_k) of (7)
is NOT the normalizing constant: int_0^1 t^i (1-t)^j dt = B(i+1, j+1), so
S_k C_k / h = 1 / B(i_k+1, i_{k+1}+1)). Hence, with i_left = i_k (the exponent
of the knot where the kernel starts) and i_right = i_{k+1},

    F(t) = I_t(i_left + 1, i_right + 1)   (regularized incomplete Beta function,
                                            scipy.special.betainc(a, b, t)),

and for integer exponents, with n = i_left + i_right + 1 (the Bernstein form),

    F(t) = sum_{k = i_left + 1}^{n} binom(n, k) t^k (1 - t)^(n - k).

Smoothness at the knots (derived from F(t) ~ t^(i_left+1) / ((i_left+1)
B(i_left+1, i_right+1)) as t -> 0+, and symmetrically at 1): F^(m) is
continuous at 0 for m <= i_left and F^(i_left + 1) jumps there (from 0 to
i_left! / B(a, b)) when i_left is an integer; for non-integer i_left,
F in C^(floor(i_left) + 1) and F^(floor(i_left) + 2) is unbounded near 0.
So F is C^m0 at 0 with m0 = i_left (integer) or floor(i_left) + 1 (otherwise),
likewise m1 from i_right at 1, and ``smoothness`` = min(m0, m1). The GERBS of
eq. (3) built from BFBS(i_{k}, i_{k+1}) on every knot interval is therefore
C^{i_k} at the knot t_k, as in [6]. i = 0 gives F'(0+) = const: the affine hat.

The paper's (8) asks i > 0; i = 0 (the affine limit) is accepted here too.
"""
from __future__ import annotations

import math
import numbers

import numpy as np

from ..errors import InvalidParameterError
from ._table import CHUNK
from .base import Kernel, as_float_array

__all__ = ["BFBS"]


# Largest exponent accepted. F is normalized by 1 / B(i_left + 1, i_right + 1),
# which leaves float64 beyond i_left + i_right ~ 1070 (B(501, 501) ~ 3.7e-303), and
# the Bernstein form's binomials binom(i_left + i_right + 1, k) beyond ~1029; at
# 500 + 500 both are still finite and F agrees with betainc to 6e-14.
MAX_EXPONENT = 500


def _exponent(name, v):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Real):
        raise InvalidParameterError(name, f"must be a real number, got {v!r}")
    v = float(v)
    if not math.isfinite(v) or not 0.0 <= v <= MAX_EXPONENT:
        raise InvalidParameterError(
            name, f"exponent must be finite and in [0, {MAX_EXPONENT}], got {v}")
    return v


def _falling(p: float, j: int) -> float:
    out = 1.0
    for i in range(j):
        out *= p - i
    return out


def _ipow(x: np.ndarray, k: int) -> np.ndarray:
    """x**k for an integer k >= 0 by repeated squaring (numpy's float pow is slow)."""
    out = np.ones_like(x)
    base = x
    while k:
        if k & 1:
            out = out * base
        k >>= 1
        if k:
            base = base * base
    return out


def _side_smoothness(i: float) -> int:
    return int(i) if i == int(i) else math.floor(i) + 1


class BFBS(Kernel):
    """BFBS kernel F(t) = I_t(i_left + 1, i_right + 1) (eqs. (4)-(7), see module doc).

    Parameters
    ----------
    i_left, i_right : float in [0, MAX_EXPONENT = 500] (integers give the Bernstein form)

    Values: for integer exponents the Bernstein form (positive terms, see
    :meth:`_bernstein`), else scipy.special.betainc (both accurate to a few
    ulps; they agree to 1e-14 -- tested). Derivatives
    F^(m) = (t^i_left (1-t)^i_right)^(m-1) / B(a, b) by the Leibniz rule in
    closed form (exact to rounding). ``max_order`` = 8.
    """

    max_order = 8

    def __init__(self, i_left=2, i_right=2):
        il = _exponent("i_left", i_left)
        ir = _exponent("i_right", i_right)
        object.__setattr__(self, "i_left", il)
        object.__setattr__(self, "i_right", ir)
        object.__setattr__(self, "smoothness", min(_side_smoothness(il), _side_smoothness(ir)))
        from scipy.special import beta as beta_fn   # (lazy: scipy.special costs 0.13 s to import)
        object.__setattr__(self, "_norm", 1.0 / float(beta_fn(il + 1.0, ir + 1.0)))

    def _params(self):
        return (self.i_left, self.i_right)

    @property
    def is_integer(self) -> bool:
        """True when both exponents are integers (Bernstein form available)."""
        return self.i_left == int(self.i_left) and self.i_right == int(self.i_right)

    def _eval_one(self, t, nu):
        if nu == 0 and not self.is_integer:
            x = np.clip(t, 0.0, 1.0)                 # NaN propagates
            from scipy.special import betainc
            return betainc(self.i_left + 1.0, self.i_right + 1.0, x)
        return np.asarray(self._eval(t, nu)[nu])

    def _eval(self, t, nmax):
        if not self.is_integer:
            return Kernel._eval(self, t, nmax)
        # integer exponents: polynomials, evaluated on all points without masks
        flat = t.reshape(-1)
        out = np.empty((nmax + 1, flat.size))
        for s in range(0, flat.size, CHUNK):         # cache-sized chunks
            tc = flat[s:s + CHUNK]
            x = np.clip(tc, 0.0, 1.0)                # NaN propagates
            out[0, s:s + CHUNK] = self._bernstein(x)
            if nmax:
                with np.errstate(invalid="ignore"):
                    inner = ((tc > 0.0) & (tc < 1.0)).astype(np.float64)
                inner[np.isnan(tc)] = np.nan
                D = self._interior(x, nmax, values=False)[1:]
                D *= inner                            # 0 outside (0, 1)
                out[1:, s:s + CHUNK] = D
        return out.reshape((nmax + 1,) + t.shape)

    def _bernstein(self, x):
        """F(x), x in [0, 1], integer exponents, in the Bernstein basis with no
        cancellation: F = (1-x)^n sum_{k >= a} C(n,k) u^k, u = x/(1-x), for
        x <= 1/2, and F = 1 - x^n sum_{j > n-a} C(n,j) v^j, v = (1-x)/x, else
        (all terms positive; relative accuracy ~ n ulps)."""
        a, n = int(self.i_left) + 1, int(self.i_left + self.i_right) + 1
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            omx = 1.0 - x
            u = x / omx
            lo = np.zeros_like(x)
            for k in range(n, a - 1, -1):            # Horner over k = n..a
                lo *= u
                lo += float(math.comb(n, k))  # (an int > 2**63 would be an object)
            lo *= _ipow(u, a)
            lo *= _ipow(omx, n)
            v = omx / x
            hi = np.zeros_like(x)
            for j in range(n, n - a, -1):            # j = n..n-a+1
                hi *= v
                hi += float(math.comb(n, j))
            hi *= _ipow(v, n - a + 1)
            hi *= _ipow(x, n)
            hi = 1.0 - hi
        return np.where(x <= 0.5, lo, hi)

    def _interior(self, x, nmax, values=True):
        p, q = self.i_left, self.i_right
        out = np.empty((nmax + 1, x.size))
        if values:
            from scipy.special import betainc
            out[0] = betainc(p + 1.0, q + 1.0, x)
        omx = 1.0 - x
        for m in range(1, nmax + 1):
            j_der = m - 1                            # derivative order of the density
            acc = np.zeros_like(x)
            for j in range(j_der + 1):
                cp = _falling(p, j)
                cq = _falling(q, j_der - j)
                if cp == 0.0 or cq == 0.0:           # integer exponent differentiated away
                    continue
                c = math.comb(j_der, j) * cp * cq * (-1.0) ** (j_der - j)
                if self.is_integer:
                    acc += c * _ipow(x, int(p - j)) * _ipow(omx, int(q - j_der + j))
                else:
                    acc += c * x ** (p - j) * omx ** (q - j_der + j)
            out[m] = self._norm * acc
        return out

    def bernstein_cdf(self, t):
        """F(t) in the Bernstein basis (integer exponents only); same shape as t.

        F(t) = sum_{k=i_left+1}^{n} binom(n, k) t^k (1-t)^(n-k), n = i_left + i_right + 1,
        for t in [0, 1]; clamped to 0 / 1 outside, NaN -> NaN.
        """
        if not self.is_integer:
            name = "i_left" if self.i_left != int(self.i_left) else "i_right"
            raise InvalidParameterError(name, "the Bernstein form needs integer exponents")
        t = as_float_array(t)
        x = np.clip(t, 0.0, 1.0)
        il, n = int(self.i_left), int(self.i_left + self.i_right + 1)
        out = np.zeros_like(x)
        for k in range(il + 1, n + 1):
            out += float(math.comb(n, k)) * x ** k * (1.0 - x) ** (n - k)
        return out[()] if out.ndim == 0 else out
