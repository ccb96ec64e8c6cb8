"""Chain rules of the size functions: gauge -> bump psi = b(g) -> partition Psi = psi / sum psi.

A *jet* is a list [f, df, d2f] up to order nu, with df (..., 2) and d2f
(..., 2, 2) derivatives with respect to whatever 2-D coordinates the inputs'
derivatives are taken in (face coordinates for mesh surfaces, the plane for
scattered points). All exact: closed-form chain and quotient rules.
"""
from __future__ import annotations

import numpy as np

__all__ = ["outer", "star_gauge_jet", "bump_jet", "partition_jet"]


def outer(a, b):
    """a b^T over the last axis: (..., 2), (..., 2) -> (..., 2, 2)."""
    return a[..., :, None] * b[..., None, :]


def star_gauge_jet(r_jet, theta_jet, u, nu: int):
    """g = r u(theta), the star gauge of eq. (62) with u = 1 / rho~ (a smooth envelope).

    r_jet, theta_jet: jets of the polar coordinates; u: [u, u', u''] (theta-derivatives
    of the reciprocal envelope) at theta. Returns the jet of g up to order nu.
    """
    r = r_jet[0]
    out = [r * u[0]]
    if nu >= 1:
        dr, dt = r_jet[1], theta_jet[1]
        out.append(u[0][..., None] * dr + (r * u[1])[..., None] * dt)
    if nu >= 2:
        Hr, Ht = r_jet[2], theta_jet[2]
        out.append(u[0][..., None, None] * Hr
                   + u[1][..., None, None] * (outer(dr, dt) + outer(dt, dr))
                   + (r * u[2])[..., None, None] * outer(dt, dt)
                   + (r * u[1])[..., None, None] * Ht)
    return out


def bump_jet(kernel, g_jet, nu: int):
    """psi = b(g) = 1 - F(g) (the GERBS bump of eq. (1)), with F the kernel's CDF."""
    g = g_jet[0]
    dF = kernel.cdf_derivs(g, nu)
    out = [1.0 - dF[0]]
    if nu >= 1:
        out.append(-dF[1][..., None] * g_jet[1])
    if nu >= 2:
        out.append(-dF[2][..., None, None] * outer(g_jet[1], g_jet[1])
                   - dF[1][..., None, None] * g_jet[2])
    return out


def partition_jet(psi_jet, nu: int, axis: int = 0):
    """Psi_k = psi_k / sum_j psi_j (eq. (27)), the sum over ``axis`` of psi_jet's arrays.

    Where every psi vanishes (a hole in the cover) the result is NaN; callers refuse
    such covers (eps0 = 0) instead of returning it.
    """
    S0 = psi_jet[0].sum(axis=axis, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        Psi = [psi_jet[0] / S0]
    if nu >= 1:
        S1 = psi_jet[1].sum(axis=axis, keepdims=True)
        Psi.append((psi_jet[1] - Psi[0][..., None] * S1) / S0[..., None])
    if nu >= 2:
        S2 = psi_jet[2].sum(axis=axis, keepdims=True)
        Psi.append((psi_jet[2] - outer(Psi[1], S1) - outer(S1, Psi[1])
                    - Psi[0][..., None, None] * S2) / S0[..., None, None])
    return Psi
