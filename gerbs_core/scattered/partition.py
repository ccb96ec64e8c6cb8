"""Partitions of unity of the general construction (paper sections 2.3-2.4, 5.3).

Functions act on *jets*: a jet is a tuple ``(v, g, h)`` with value ``v`` (..., K),
gradient ``g`` (..., K, n) and Hessian ``h`` (..., K, n, n) (None when not needed),
where the axis K runs over the candidate elements at each evaluation point
(neighbour sums only, Remark 12). Unused candidate slots carry zero jets.

* :func:`normalize`          Psi_i = psi_i / sum_k psi_k                         (27)
* :func:`general_basis`      B_i = Phi_i + Psi_i Phi_0 with Phi from (29)-(30)   (32)
* :func:`disjoint_basis`     B_i = phi_i + Psi_i (1 - sum_k phi_k), (35): (32) when the
  phi supports are disjoint (34), without the ordered product
  (``phi = psi`` gives the maximally supported variant (67), Theorem 4;
  ``phi = 0`` gives B = Psi, the minimally supported (73), Theorem 6)
* :func:`basis_33`, :func:`basis_35`, :func:`basis_36`: the equivalent forms
  (33), (35), (36) on full (..., N) value arrays, for checking the equivalences.

All formulas are exact algebra (no approximation); derivatives follow from the
product and quotient rules.
"""
from __future__ import annotations

import numpy as np

__all__ = ["jmul", "jrecip", "normalize", "general_basis", "disjoint_basis", "basis_33", "basis_35", "basis_36",
           "minimal_basis"]


def _outer(a, b):
    return a[..., :, None] * b[..., None, :]


def jmul(a, b, nu):
    """Jet of the product a*b."""
    v = a[0] * b[0]
    g = h = None
    if nu >= 1:
        g = a[1] * b[0][..., None] + a[0][..., None] * b[1]
    if nu >= 2:
        h = (a[2] * b[0][..., None, None] + a[0][..., None, None] * b[2]
             + _outer(a[1], b[1]) + _outer(b[1], a[1]))
    return v, g, h


def jrecip(a, nu):
    """Jet of 1/a (a != 0)."""
    r = 1.0 / a[0]
    g = h = None
    if nu >= 1:
        g = -a[1] * (r ** 2)[..., None]
    if nu >= 2:
        h = -a[2] * (r ** 2)[..., None, None] + 2.0 * _outer(a[1], a[1]) * (r ** 3)[..., None, None]
    return r, g, h


def jsum(a, nu, axis=-1):
    """Jet of the sum over the candidate axis (the last axis of the value)."""
    v = a[0].sum(axis=-1)
    g = a[1].sum(axis=-2) if nu >= 1 else None
    h = a[2].sum(axis=-3) if nu >= 2 else None
    return v, g, h


def _expand(a, nu):
    """Add the candidate axis back to a summed jet (for broadcasting)."""
    return (a[0][..., None],
            a[1][..., None, :] if nu >= 1 else None,
            a[2][..., None, :, :] if nu >= 2 else None)


def normalize(psi, nu):
    """Psi_i = psi_i / sum_k psi_k, eq. (27), with derivatives up to ``nu``.

    Where the sum vanishes (outside every support) the result is NaN.
    """
    S = jsum(psi, nu)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = jrecip(S, nu)
        return jmul(psi, _expand(inv, nu), nu)


def minimal_basis(psi, nu):
    """B_i = Psi_i: minimally supported non-degeneracy phi = 0, eq. (73), Theorem 6."""
    return normalize(psi, nu)


def general_basis(phi, psi, nu):
    """B_i = Phi_i + Psi_i Phi_0 (32), Phi_i = phi_i prod_{j<i} (1 - phi_j) (29),
    Phi_0 = prod_j (1 - phi_j) (30).

    The candidate axis must be sorted by the global index i (the products run over
    j < i); padded slots must have zero phi and psi. With ``phi is psi`` this is the
    maximally supported basis (67).
    """
    Psi = normalize(psi, nu)
    K = phi[0].shape[-1]
    one_minus = (1.0 - phi[0],
                 -phi[1] if nu >= 1 else None,
                 -phi[2] if nu >= 2 else None)
    lead = phi[0].shape[:-1]
    n = phi[1].shape[-1] if nu >= 1 else 0
    P = (np.ones(lead),
         np.zeros(lead + (n,)) if nu >= 1 else None,
         np.zeros(lead + (n, n)) if nu >= 2 else None)
    Phi_v = np.empty(phi[0].shape)
    Phi_g = np.empty(phi[1].shape) if nu >= 1 else None
    Phi_h = np.empty(phi[2].shape) if nu >= 2 else None
    for k in range(K):
        pk = (phi[0][..., k],
              phi[1][..., k, :] if nu >= 1 else None,
              phi[2][..., k, :, :] if nu >= 2 else None)
        t = jmul(pk, P, nu)
        Phi_v[..., k] = t[0]
        if nu >= 1:
            Phi_g[..., k, :] = t[1]
        if nu >= 2:
            Phi_h[..., k, :, :] = t[2]
        ok = (one_minus[0][..., k],
              one_minus[1][..., k, :] if nu >= 1 else None,
              one_minus[2][..., k, :, :] if nu >= 2 else None)
        P = jmul(P, ok, nu)
    # P is now Phi_0 (30)
    PsiPhi0 = jmul(Psi, _expand(P, nu), nu)
    v = Phi_v + PsiPhi0[0]
    g = Phi_g + PsiPhi0[1] if nu >= 1 else None
    h = Phi_h + PsiPhi0[2] if nu >= 2 else None
    return v, g, h


def disjoint_basis(phi, psi, nu):
    """B_i = phi_i + Psi_i (1 - sum_k phi_k), eq. (35), with derivatives up to ``nu``.

    Equal to (32) when the phi supports are disjoint (34) (then Phi_i = phi_i and
    Phi_0 = 1 - sum phi); any candidate order.
    """
    Psi = normalize(psi, nu)
    S = jsum(phi, nu)
    rest = (1.0 - S[0], -S[1] if nu >= 1 else None, -S[2] if nu >= 2 else None)
    PR = jmul(Psi, _expand(rest, nu), nu)
    return tuple(None if a is None else a + b for a, b in zip(phi, PR))


# ---- equivalent forms on full arrays (values only), for the equivalence tests ----

def basis_33(phi, psi):
    """Eq. (33): B_i = prod_{j<i}(1-phi_j) [phi_i + psi_i/sum psi * prod_{j>=i}(1-phi_j)]."""
    om = 1.0 - phi
    before = np.cumprod(np.concatenate([np.ones(phi.shape[:-1] + (1,)), om[..., :-1]], -1), -1)
    from_i = np.flip(np.cumprod(np.flip(om, -1), -1), -1)        # prod_{j>=i}
    S = psi.sum(-1, keepdims=True)
    return before * (phi + psi / S * from_i)


def basis_35(phi, psi):
    """Eq. (35), valid when the phi supports are disjoint (34):
    B_i = phi_i + psi_i / sum psi * (1 - sum phi)."""
    S = psi.sum(-1, keepdims=True)
    return phi + psi / S * (1.0 - phi.sum(-1, keepdims=True))


def basis_36(phi, psi):
    """Eq. (36), valid under (34):
    B_i = [ (sum_{j!=i} psi_j) phi_i + (1 - sum_{j!=i} phi_j) psi_i ] / sum psi."""
    S = psi.sum(-1, keepdims=True)
    P = phi.sum(-1, keepdims=True)
    return ((S - psi) * phi + (1.0 - (P - phi)) * psi) / S
