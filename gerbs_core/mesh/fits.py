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

:func:`candidate_fits` makes the data fits of one candidate rule (degree and
data rings, :mod:`gerbs_core.mesh.rings`) for all vertices at once, batched by
the number of data.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .monomials import bending_gram, monomial_exponents, monomials, n_monomials

__all__ = ["RCOND", "CANDIDATES", "pinned_normal_inverse", "candidate_fits", "CandidateFits"]

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


def _condition(rings, degree, cnt, layers):
    """(V,) condition numbers of the fits' normal matrices on rings <= layers, in scaled
    monomials (the original design's criterion)."""
    V = len(cnt)
    out = np.full(V, np.inf)
    pad = 2 ** np.ceil(np.log2(np.maximum(cnt, 1))).astype(np.int64)
    for n in np.unique(pad).tolist():
        vs = np.flatnonzero(pad == n)
        k = np.arange(n)[None, :]
        idx = rings.offsets[vs][:, None] + np.minimum(k, cnt[vs][:, None] - 1)
        use = (k < cnt[vs][:, None]) & (rings.ring[idx] <= layers)
        y = rings.y[idx] / rings.h[vs][:, None, None]
        w = _data_weights(y, use)
        B = monomials(y, degree)[0]
        lam = np.linalg.eigvalsh(np.einsum("kn,knm,knl->kml", w, B, B))
        out[vs] = lam[:, -1] / np.maximum(lam[:, 0], 1e-300)
    return out


def _data_weights(y, use):
    """1 / |y|^2 for scaled chart positions y (h = 1) of the data used, 0 elsewhere: near
    data count more (the fit is used near its vertex)."""
    d = np.hypot(y[..., 0], y[..., 1])
    return np.where(use & (d > 0), 1.0 / np.where(d > 0, d, 1.0) ** 2, 0.0)


def candidate_fits(rings, degree: int, layers: int) -> CandidateFits:
    """Data fits of `degree` on rings <= `layers`, batched by data count. A ring-1 fit takes
    ring 2 as well where ring 1 has fewer than M + 2 data (M the number of coefficients) or
    leaves the fit ill-conditioned (normal-matrix condition above ``MAX_CONDITION``: one-sided
    boundary stars); a fit on rings 1-2 takes ring 3 where they hold fewer than M + 2 data."""
    V = len(rings.offsets) - 1
    M = n_monomials(degree)
    deg_of = monomial_exponents(degree).sum(1)
    cnt = np.diff(rings.offsets)
    owner = np.repeat(np.arange(V), cnt)
    n1 = np.bincount(owner[rings.ring == 1], minlength=V)
    n2 = np.bincount(owner[rings.ring <= 2], minlength=V)
    wider = 3 if np.any(rings.ring == 3) else 2
    use_layers = np.full(V, layers)
    if layers < 2:
        use_layers = np.where((n1 < M + 2) | (_condition(rings, degree, cnt, 1) > MAX_CONDITION),
                              2, use_layers)
    use_layers = np.where((use_layers == 2) & (n2 < M + 2), wider, use_layers)
    normal = np.zeros((V, M, M))
    rows, cols, vals, hrows, hcols, hvals = [], [], [], [], [], []
    # batches of equal padded length (powers of two): little padding for high valences
    pad = 2 ** np.ceil(np.log2(np.maximum(cnt, 1))).astype(np.int64)
    for n in np.unique(pad).tolist():
        vs = np.flatnonzero(pad == n)
        k = np.arange(n)[None, :]
        idx = rings.offsets[vs][:, None] + np.minimum(k, cnt[vs][:, None] - 1)
        real = k < cnt[vs][:, None]
        y = rings.y[idx] / rings.h[vs][:, None, None]
        use = real & (rings.ring[idx] <= use_layers[vs][:, None])
        w = _data_weights(y, use)
        w /= np.maximum(w.sum(1, keepdims=True), 1e-300)  # per vertex: weights sum to 1
        B = monomials(y, degree)[0]                          # (K, n, M)
        N = np.einsum("kn,knm,knl->kml", w, B, B)
        normal[vs] = N
        Pinv = pinned_normal_inverse(N, degree)
        Ws = Pinv @ np.swapaxes(B * w[..., None], 1, 2)      # (K, M, n): scaled coefficients
        A = Ws / rings.h[vs][:, None, None] ** deg_of[None, :, None]
        r = vs[:, None, None] * M + np.arange(M)[None, :, None]
        q = rings.ids[idx][:, None, :]
        keep = np.broadcast_to(use[:, None, :], A.shape)
        rows.append(np.broadcast_to(r, A.shape)[keep])
        cols.append(np.broadcast_to(q, A.shape)[keep])
        vals.append(A[keep])
        # the pin: - sum_j A_j X_v
        rows.append((vs[:, None] * M + np.arange(M)).ravel())
        cols.append(np.repeat(vs, M))
        vals.append(-(A * use[:, None, :]).sum(2).ravel())
        # right-hand sides B^T W (X_q - X_v) of the scaled normal equations
        bw = np.swapaxes(B * w[..., None], 1, 2)             # (K, M, n)
        hrows.append(np.broadcast_to(r, bw.shape)[keep])
        hcols.append(np.broadcast_to(q, bw.shape)[keep])
        hvals.append(bw[keep])
        hrows.append((vs[:, None] * M + np.arange(M)).ravel())
        hcols.append(np.repeat(vs, M))
        hvals.append(-bw.sum(2).ravel())
    shape = (V * M, V)
    matrix = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                           shape=shape)
    rhs = sp.csr_matrix((np.concatenate(hvals), (np.concatenate(hrows), np.concatenate(hcols))),
                        shape=shape)
    return CandidateFits(degree, matrix, normal, rhs)
