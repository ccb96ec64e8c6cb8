"""Pinned least-squares fits of local polynomials, as linear operators of the positions.

A local function of vertex v is l_v(y) = X_v + sum_m c_{v,m} y^m (degree 1..d
monomials, :mod:`gerbs_core.mesh.monomials`), so l_v(0) = X_v exactly: the
surface interpolates v (eq. (73) with B_v = 1 near v). Its coefficients solve
a weighted least-squares problem whose targets are linear in the vertex
positions; among the minimisers the fit takes the smoothest polynomial in the
rotation-invariant bending metric of :func:`~gerbs_core.mesh.monomials.bending_gram`,
with directions whose normal-matrix eigenvalue is below ``RCOND`` times the
largest treated as undetermined. A fit therefore does not depend on how its
chart is rotated (the surface does not depend on the vertex or face
numbering) and reproduces every polynomial of its degree exactly when the data
determine one (flat-mesh reproduction).

:func:`candidate_fits_all` makes the data fits of the candidate rules (degree and
data rings, :mod:`gerbs_core.mesh.rings`) for all vertices at once, batched by
the number of data.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .monomials import bending_gram, monomial_exponents, monomials, n_monomials

__all__ = ["RCOND", "CANDIDATES", "pinned_normal_inverse", "candidate_fits",
           "candidate_fits_all", "CandidateFits"]

# relative eigenvalue cut-off of the normal matrices (in the bending metric, scaled
# coordinates y / h): a normal-matrix eigenvalue of 1e-8 is a singular value of 1e-4 of
# the weighted design, the conditioning below which a fit follows round-off or noise
RCOND = 1e-8

# the normal-matrix condition beyond which a ring-1 fit takes ring 2 too (the original
# design's design-matrix limit of ~100, squared)
MAX_CONDITION = 1e4

# the candidate rules (degree, data rings) each vertex chooses from (mesh.agreement)
CANDIDATES = ((2, 1), (3, 1), (3, 2), (4, 2))


def pinned_normal_inverse(N: np.ndarray, degree: int) -> np.ndarray:
    """Truncated pseudo-inverses (K, M, M) of normal matrices N (K, M, M) of scaled-monomial
    fits, in the bending metric: c = P @ (B^T W t) is the smoothest minimiser."""
    G = bending_gram(degree)
    L = np.linalg.cholesky(G)
    Li = np.linalg.inv(L)                       # G = L L^T; coordinates z = L^T c
    Nz = Li @ N @ Li.T
    lam, Q = np.linalg.eigh(Nz)
    top = lam[..., -1:]
    inv = np.where(lam > RCOND * np.maximum(top, 1e-300), 1.0 / np.where(lam > 0, lam, 1.0), 0.0)
    Pz = (Q * inv[..., None, :]) @ np.swapaxes(Q, -1, -2)
    return Li.T @ Pz @ Li


class CandidateFits:
    """The data fits of one rule for all vertices: coefficients c_v = A_v (X_N - X_v).

    ``degree``; ``matrix`` (V*M, V) sparse, rows v*M + m: the coefficient operator in
    UNSCALED chart coordinates (pin included: c = matrix @ X). ``normal`` (V, M, M):
    the data normal matrices in scaled coordinates y / h_v (for the coupled fits of
    :mod:`gerbs_core.mesh.agreement`), ``rhs`` (V*M, V) sparse: their right-hand sides.
    """

    def __init__(self, degree, matrix, normal, rhs):
        self.degree, self.matrix, self.normal, self.rhs = degree, matrix, normal, rhs


def _data_weights(y, use):
    """1 / |y|^2 for scaled chart positions y (h = 1) of the data used, 0 elsewhere: near
    data count more (the fit is used near its vertex)."""
    d = np.hypot(y[..., 0], y[..., 1])
    return np.where(use & (d > 0), 1.0 / np.where(d > 0, d, 1.0) ** 2, 0.0)


def _normal(B, w):
    """Normal matrices (K, M, M) = B^T diag(w) B of designs B (K, n, M), weights w (K, n)."""
    return np.swapaxes(B * w[..., None], 1, 2) @ B


def candidate_fits(rings, degree: int, layers: int) -> CandidateFits:
    """The data fits of one rule (:func:`candidate_fits_all`)."""
    return candidate_fits_all(rings, [(degree, layers)])[0]


def candidate_fits_all(rings, rules) -> list:
    """Data fits of every rule (degree, layers) in ``rules``, batched by data count (the
    batches' chart positions and monomials shared by all rules).

    A ring-1 fit takes ring 2 as well where ring 1 has fewer than M + 2 data (M the number
    of coefficients) or leaves the fit ill-conditioned (normal-matrix condition above
    ``MAX_CONDITION``, scaled monomials: one-sided boundary stars); a fit on rings 1-2
    takes ring 3 where they hold fewer than M + 2 data."""
    V = len(rings.offsets) - 1
    dmax = max(d for d, _ in rules)
    cnt = np.diff(rings.offsets)
    owner = np.repeat(np.arange(V), cnt)
    n1 = np.bincount(owner[rings.ring == 1], minlength=V)
    n2 = np.bincount(owner[rings.ring <= 2], minlength=V)
    wider = 3 if np.any(rings.ring == 3) else 2
    out = []
    acc = [{"normal": np.zeros((V, n_monomials(d), n_monomials(d))), "rows": [], "cols": [],
            "vals": [], "hvals": []} for d, _ in rules]
    # batches of equal padded length (powers of two): little padding for high valences
    pad = 2 ** np.ceil(np.log2(np.maximum(cnt, 1))).astype(np.int64)
    for n in np.unique(pad).tolist():
        vs = np.flatnonzero(pad == n)
        k = np.arange(n)[None, :]
        idx = rings.offsets[vs][:, None] + np.minimum(k, cnt[vs][:, None] - 1)
        real = k < cnt[vs][:, None]
        ring = rings.ring[idx]
        y = rings.y[idx] / rings.h[vs][:, None, None]
        Ball = monomials(y, dmax)[0]                          # (K, n, M_max)
        q = rings.ids[idx]
        for (degree, layers), a in zip(rules, acc):
            M = n_monomials(degree)
            B = Ball[..., :M]
            use_layers = np.full(len(vs), layers)
            if layers < 2:
                N1 = _normal(B, _data_weights(y, real & (ring <= 1)))
                lam = np.linalg.eigvalsh(N1)
                cond = lam[:, -1] / np.maximum(lam[:, 0], 1e-300)
                use_layers = np.where((n1[vs] < M + 2) | (cond > MAX_CONDITION), 2, use_layers)
            use_layers = np.where((use_layers == 2) & (n2[vs] < M + 2), wider, use_layers)
            use = real & (ring <= use_layers[:, None])
            w = _data_weights(y, use)
            w /= np.maximum(w.sum(1, keepdims=True), 1e-300)  # per vertex: weights sum to 1
            bw = np.swapaxes(B * w[..., None], 1, 2)          # (K, M, n)
            N = bw @ B
            a["normal"][vs] = N
            Pinv = pinned_normal_inverse(N, degree)
            deg_of = monomial_exponents(degree).sum(1)
            A = (Pinv @ bw) / rings.h[vs][:, None, None] ** deg_of[None, :, None]  # unscaled
            kk, nn = np.nonzero(use)
            r = vs[:, None] * M + np.arange(M)[None, :]         # (K, M) rows
            # data entries (one per used datum and monomial), then the pins - sum_j A_j X_v
            a["rows"] += [r[kk].ravel(), r.ravel()]
            a["cols"] += [np.repeat(q[kk, nn], M), np.repeat(vs, M)]
            a["vals"] += [A[kk, :, nn].ravel(), -(A * use[:, None, :]).sum(2).ravel()]
            # right-hand sides B^T W (X_q - X_v) of the scaled normal equations
            a["hvals"] += [bw[kk, :, nn].ravel(), -bw.sum(2).ravel()]
    for (degree, _), a in zip(rules, acc):
        shape = (V * n_monomials(degree), V)
        rows, cols = np.concatenate(a["rows"]), np.concatenate(a["cols"])
        matrix = sp.csr_matrix((np.concatenate(a["vals"]), (rows, cols)), shape=shape)
        rhs = sp.csr_matrix((np.concatenate(a["hvals"]), (rows, cols)), shape=shape)
        out.append(CandidateFits(degree, matrix, a["normal"], rhs))
    return out
