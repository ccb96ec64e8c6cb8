"""Chain rules of the size functions: gauge -> bump psi = b(g) -> partition Psi = psi / sum psi.

A *jet* is a list [f, df, d2f] up to order nu, with df (..., n) and d2f
(..., n, n) derivatives with respect to whatever coordinates the inputs'
derivatives are taken in (face coordinates for mesh surfaces, the plane or R^n for
scattered points). All exact: closed-form chain and quotient rules. This is the one
implementation of g -> psi for every cover (mesh stars, planar and n-D star covers,
ball covers of every metric).
"""
from __future__ import annotations

import numpy as np

__all__ = ["outer", "polar_jet", "star_gauge_jet", "bump_derivs", "chain_jet", "bump_jet",
           "partition_jet"]


def outer(a, b):
    """a b^T over the last axis: (..., 2), (..., 2) -> (..., 2, 2)."""
    return a[..., :, None] * b[..., None, :]


def polar_jet(y, nu: int):
    """Jets of the polar coordinates r = |y|, theta = atan2(y1, y0) at y (..., 2) of the
    plane: dr = e_r, Hr = e_t e_t^T / r, dtheta = e_t / r,
    Htheta = -(e_r e_t^T + e_t e_r^T) / r^2. At y = 0 (no direction) the derivatives are
    taken along e_r = (1, 0) with r replaced by 1; callers mask that point."""
    r = np.hypot(y[..., 0], y[..., 1])
    r_jet, t_jet = [r], [np.arctan2(y[..., 1], y[..., 0])]
    if nu >= 1:
        safe = np.where(r > 0, r, 1.0)
        er = np.where((r > 0)[..., None], y / safe[..., None], np.array([1.0, 0.0]))
        et = np.stack([-er[..., 1], er[..., 0]], -1)
        r_jet.append(er)
        t_jet.append(et / safe[..., None])
    if nu >= 2:
        r_jet.append(outer(et, et) / safe[..., None, None])
        t_jet.append(-(outer(er, et) + outer(et, er)) / (safe * safe)[..., None, None])
    return r_jet, t_jet


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


def bump_derivs(kernel, t, nu: int):
    """[b, b', b''][:nu + 1] of the GERBS bump b = 1 - F on [0, 1), 0 beyond (eq. (1)), at
    t >= 0: the kernel's own :meth:`~gerbs_core.kernels.base.Kernel.bump_derivs`, set to
    exactly 0 (values and derivatives) for t >= 1, where the support ends."""
    b = kernel.bump_derivs(np.minimum(t, 1.0), max(nu, 0))
    inside = t < 1.0
    return [np.where(inside, b[k], 0.0) for k in range(nu + 1)]


def chain_jet(bt, g_jet, nu: int):
    """Jet of b(g(y)) from [b, b', b''] at g and g's jet: d(b o g) = b' dg,
    d2(b o g) = b'' dg dg^T + b' d2g."""
    out = [bt[0]]
    if nu >= 1:
        out.append(bt[1][..., None] * g_jet[1])
    if nu >= 2:
        out.append(bt[2][..., None, None] * outer(g_jet[1], g_jet[1])
                   + bt[1][..., None, None] * g_jet[2])
    return out


def bump_jet(kernel, g_jet, nu: int):
    """psi = b(g) = 1 - F(g) (the GERBS bump of eq. (1)), 0 for g >= 1."""
    return chain_jet(bump_derivs(kernel, g_jet[0], nu), g_jet, nu)


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
