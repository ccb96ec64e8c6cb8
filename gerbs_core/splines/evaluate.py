"""The one evaluator of GERBS splines s(t) = sum_j G_j(t) l_j(t) (eq. (3)).

On a knot interval [t_k, t_{k+1}] of length h only two basis functions of eq. (3)
are non-zero: the falling G_k = 1 - F_{k+1} and the rising G_{k+1} = F_{k+1}, with
F_{k+1}(t) = F(w), w = (t - t_k) / h, the kernel's CDF moved to the interval. So the
spline there is the transition between the two neighbouring local functions

    s = (1 - F(w)) l_k + F(w) l_{k+1},

and by the Leibniz rule (the falling G_k^(i) = -F^(i) for i >= 1), with
D = l_{k+1} - l_k,

    s^(nu) = (1 - F(w)) l_k^(nu) + F(w) l_{k+1}^(nu)
             + sum_{i=1..nu} C(nu, i) F^(i)(w) h^(-i) D^(nu - i).

Every GERBS spline of the package is evaluated here: curves (:mod:`.curves`), the
radial envelopes of star gauges (:mod:`gerbs_core.gauge.envelope`, the packed
:class:`~gerbs_core.gauge.envelope_table.EnvelopeTable`) and the planar star covers
of scattered points (:mod:`gerbs_core.scattered.planar_star`). Callers find the knot
interval of each point (:func:`knot_interval`, or their own structure), and pass the
jets of the two local functions there. Exact given the kernel's derivatives: only
rounding enters.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["knot_interval", "rising_jet", "falling_jet", "blend_jet", "spline_jet"]


def knot_interval(knots, t, side: str = "left"):
    """Index k of the knot interval of each t: int array of t's shape.

    side="left": t in (t_k, t_{k+1}] (left-continuous basis, :mod:`.curves`; -1 left
    of t_0, len(knots) - 1 right of the last knot); side="right": t in [t_k, t_{k+1}).
    """
    return np.searchsorted(knots, t, side=side) - 1


def rising_jet(kernel, w, h, nu: int):
    """The rising B-function F(w) of a knot interval of length h and its t-derivatives.

    w : (...) the interval's local coordinate (t - t_k) / h; h : broadcastable to w.
    Returns (nu + 1, ...) float64: F^(i)(w) / h^i, i = 0..nu (chain rule, exact given
    the kernel's derivatives). The falling one is :func:`falling_jet`.
    """
    w = np.asarray(w, dtype=np.float64)
    # (1-d input: some kernels mishandle 0-d arrays)
    F = kernel.cdf_derivs(np.atleast_1d(w), nu).reshape((nu + 1,) + w.shape)
    hinv = 1.0 / np.asarray(h, dtype=np.float64)
    hp = np.ones_like(hinv)
    for i in range(1, nu + 1):
        hp = hp * hinv
        F[i] = F[i] * hp
    return F


def falling_jet(rise):
    """1 - F and its derivatives from the rising jet (nu + 1, ...): the falling G_k."""
    fall = -np.asarray(rise)
    fall[0] += 1.0
    return fall


def blend_jet(left, right, rise, nu: int):
    """s^(nu) of s = (1 - F) l_k + F l_{k+1} by the Leibniz rule (module docstring).

    left, right : (nu + 1, *S) jets of the two local functions (sequences of arrays
        allowed), derivatives with respect to t.
    rise : (nu + 1, *S') the rising jet (:func:`rising_jet`), S' broadcastable to S
        (add trailing axes for vector-valued local functions).
    Returns (nu + 1, *S) float64.

    The terms of F itself are summed in the convex form (1 - F) l^(nu)_k + F l^(nu)_{k+1},
    so that s^(nu) equals l_k^(nu) where F = 0 and l_{k+1}^(nu) where F = 1 to the last
    bit (exact Hermite interpolation at the knots for flat kernels, Lemma 3 (ii)); the
    terms of F's derivatives, where -F^(i) l_k + F^(i) l_{k+1} would cancel two large
    numbers when h is small, as F^(i) h^-i (l_{k+1} - l_k)^(nu-i).
    """
    fall0 = 1.0 - rise[0]
    D = [np.asarray(b) - a for a, b in zip(left[:nu], right[:nu])]
    out = np.empty((nu + 1,) + np.broadcast(np.asarray(left[0]), np.asarray(rise[0])).shape)
    for n in range(nu + 1):
        acc = fall0 * left[n] + rise[0] * right[n]
        for i in range(1, n + 1):
            acc += (math.comb(n, i) * rise[i]) * D[n - i]
        out[n] = acc
    return out


def spline_jet(kernel, w, h, left, right, nu: int):
    """The spline and its derivatives 0..nu at points of knot intervals of length h.

    w (...) local coordinates, h broadcastable to w, left / right (nu + 1, ...) jets
    of the interval's two local functions (as :func:`blend_jet`). Returns
    (nu + 1, ...).
    """
    return blend_jet(left, right, rising_jet(kernel, w, h, nu), nu)
