"""The reciprocal envelope u~ = 1/rho~ of a star gauge as a GERBS spline of polar lines.

The local functions of the envelope (eq. (62)'s rho~, DESIGN section 4) are polar lines

    u_j(theta) = a_j cos(theta - m_j) + b_j,

the reciprocal radius of a straight line (b = 0, a = 1/distance) or of a circle about
the centre (a = 0). u~ = sum_j G_j u_j is evaluated by the one GERBS spline evaluator
(:func:`gerbs_core.splines.evaluate.spline_jet`); rho~ = 1/u~ by the reciprocal rule.
Used by :class:`~gerbs_core.gauge.envelope.RadialEnvelope`, the packed
:class:`~gerbs_core.gauge.envelope_table.EnvelopeTable` and the planar star covers of
scattered points. Exact to rounding.
"""
from __future__ import annotations

import numpy as np

from ..splines.evaluate import knot_interval, spline_jet

__all__ = ["line_jet", "envelope_u", "pieces_u", "reciprocal_derivs"]


def line_jet(a, m, b, theta, nu: int):
    """u = a cos(theta - m) + b and its theta-derivatives: array (nu + 1, *shape), the
    arguments broadcast together (b may be None for lines through no circle term)."""
    p = np.asarray(theta, dtype=np.float64) - m
    out = np.empty((nu + 1,) + np.broadcast(p, a).shape)
    out[0] = a * np.cos(p)
    if nu >= 1:
        s = a * np.sin(p)          # the cycle a cos, -a sin, -a cos, a sin
        for i in range(1, nu + 1):
            out[i] = -s if i % 4 == 1 else (-out[0] if i % 4 == 2 else s)
    if b is not None:
        out[0] += b
    return out


def pieces_u(x, t0, t1, m0, m1, A0, A1, B0, B1, kernel, nmax, exact):
    """u~ and its derivatives (nmax + 1, *x.shape) at x on the knot intervals [t0, t1]
    (all arrays of x's shape) between the lines u_0 = A0 cos(x - m0) + B0 and u_1
    likewise. ``exact``: no blending (u_0 itself: the kinked exact radius)."""
    left = line_jet(A0, m0, B0, x, nmax)
    if exact:
        return left
    right = line_jet(A1, m1, B1, x, nmax)
    h = t1 - t0
    return spline_jet(kernel, (x - t0) / h, h, left, right, nmax)


def envelope_u(x, t, m, A, B, kernel, nmax, exact):
    """u~ = sum_j G_j u_j (eq. (3)) and its derivatives at x for one envelope: knots t
    (n,), lines (m, A, B) (n,) at the knots; intervals [t_j, t_{j+1}), the end
    intervals extended."""
    j = np.clip(knot_interval(t, x, side="right"), 0, len(t) - 2)
    return pieces_u(x, t[j], t[j + 1], m[j], m[j + 1], A[j], A[j + 1], B[j], B[j + 1],
                    kernel, nmax, exact)


def reciprocal_derivs(u):
    """Derivatives of 1/u from those of u (orders 0..3), stacked like ``u``."""
    nmax = len(u) - 1
    out = np.empty((nmax + 1,) + np.shape(u[0]))
    inv = 1.0 / u[0]
    out[0] = inv
    if nmax >= 1:
        out[1] = -u[1] * inv ** 2
    if nmax >= 2:
        out[2] = 2 * u[1] ** 2 * inv ** 3 - u[2] * inv ** 2
    if nmax >= 3:
        out[3] = -u[3] * inv ** 2 + 6 * u[1] * u[2] * inv ** 3 - 6 * u[1] ** 3 * inv ** 4
    return out
