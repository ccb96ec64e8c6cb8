"""Sparse stencils W of blending surfaces: every output point as a fixed combination of vertices.

S(p) = sum_k Psi_k(p) l_{u_k}(zeta(p)) and l_u(y) = X_u + mono(y) . A_u (X_{N_u} - X_u)
is linear in the vertex positions X, so the tessellated points are W @ X with

    W[p, u_k]  += Psi_k(p) (1 - sum_j T_kj(p)),   W[p, N_u,j] += Psi_k(p) T_kj(p),
    T_k(p) = mono(zeta_{u_k}(p)) . A_{u_k}.

Mode "regular": W depends only on topology and settings (rebuild only when they
change); mode "metric": also on the rest positions bound at construction.

Locality (exact, tested): row p (a sample of face f) has non-zeros only in the
columns of L_f = union over the corners u of f of {u} and u's fit data N_u, and
N_u lies within the corners of the faces at face-distance <= 2 from u's star
(star faces + up to two enlargement layers across edges). Changing X_w changes
only samples of faces having a corner u with w in {u} or N_u; in particular only
samples of faces within face-distance 3 of w's star (star, blending: one more
ring of faces).

Assembly is vectorized: per face-size class the rows of a face are one dense
block over the face's local columns L_f, written straight into CSR form (each
sample belongs to exactly one face: no duplicate summation).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

__all__ = ["Stencil", "assemble_csr"]


@dataclass(frozen=True)
class Stencil:
    """matrix: csr (P, V); triangles (T,3); vertex_samples (V,): output point of each vertex."""

    matrix: sp.csr_matrix
    triangles: np.ndarray
    vertex_samples: np.ndarray

    def apply(self, X) -> np.ndarray:
        """Output points (P, 3) = W @ X for vertex positions X (V, 3) (any (V, k)).

        Computed as k CSR mat-vecs on the contiguous columns of X: the same sums as
        ``W @ X`` (bitwise), measured ~1.4x faster than scipy's csr @ (V, 3) on
        Suzanne at 124k rows (2 cores, single-threaded scipy).
        """
        X = np.asarray(X, dtype=np.float64)
        W = self.matrix
        if X.ndim != 2:
            return W @ X
        XT = np.ascontiguousarray(X.T)
        out = np.empty((W.shape[0], X.shape[1]))
        for k in range(X.shape[1]):
            out[:, k] = W @ XT[k]
        return out

    @property
    def nnz_per_row(self) -> float:
        return self.matrix.nnz / max(self.matrix.shape[0], 1)


def _local_columns(cand: np.ndarray):
    """Per row unique ids of cand (F, K) (-1 = padding). Returns (L (F, m), pos (F, K)).

    L[f, pos[f, i]] == cand[f, i]; each row's valid ids come first (sorted), then
    -1 (padding entries map to that one column; it collects only zero weights).
    """
    big = np.iinfo(np.int64).max
    c = np.where(cand < 0, big, cand)  # padding sorts last
    order = np.argsort(c, axis=1, kind="stable")
    sc = np.take_along_axis(c, order, axis=1)
    new = np.ones(sc.shape, dtype=bool)
    new[:, 1:] = sc[:, 1:] != sc[:, :-1]
    rank = np.cumsum(new, axis=1) - 1
    pos = np.empty_like(rank)
    np.put_along_axis(pos, order, rank, axis=1)
    m = int(rank[:, -1].max()) + 1
    L = np.full((cand.shape[0], m), -1, dtype=np.int64)
    rows = np.broadcast_to(np.arange(cand.shape[0])[:, None], sc.shape)
    ok = new & (sc != big)
    L[rows[ok], rank[ok]] = sc[ok]
    return L, pos


def assemble_csr(blocks, ids, coef, n_points: int, n_vertices: int) -> sp.csr_matrix:
    """W from per-class blocks (faces, sel, u, Psi, mono) of the surface machinery.

    faces (F,), sel (F,P) sample index or -1, u (n,F) corner vertices, Psi (n,F,P),
    mono (n,F,P,M); ids (V,N) / coef (V,M,N) the local fits.

    Faces are further grouped by their number c of local columns, so every group's
    rows are rectangular (rows x c) blocks: no padding is computed or masked out.
    """
    N = ids.shape[1]
    K = 1 + N
    # pass 1: the local columns of every face, hence each row's nnz and indptr
    cols = []
    nnz_row = np.zeros(n_points, dtype=np.int64)
    for faces, sel, u, Psi, mono in blocks:
        n, F = u.shape
        cand = np.concatenate([u[:, :, None], ids[u]], axis=2)  # (n, F, 1+N)
        L, pos = _local_columns(np.transpose(cand, (1, 0, 2)).reshape(F, n * K))
        cnt = (L >= 0).sum(axis=1)  # valid local columns of each face: 0 .. cnt-1
        nnz_row[sel[sel >= 0]] = np.broadcast_to(cnt[:, None], sel.shape)[sel >= 0]
        cols.append((L, pos, cnt))
    indptr = np.zeros(n_points + 1, dtype=np.int64)
    np.cumsum(nnz_row, out=indptr[1:])
    nnz = int(indptr[-1])
    # rows another face owns (sel -1) all go to a scratch tail (no masked copies)
    tail = max((int(L.shape[1]) for L, _, _ in cols), default=0)
    data = np.empty(nnz + tail)
    indices = np.empty(nnz + tail, dtype=np.int32)
    # pass 2: W = [Psi_k mono_k, Psi_k]_k @ C per face, one batched matmul per group of
    # faces with equal column count c: l_{u_k} = X_u + mono . A (X_N - X_u) written in
    # the face's local columns; each row comes from exactly one face, so the blocks
    # go straight to their CSR positions
    for (faces, sel, u, Psi, mono), (L, pos, cnt) in zip(blocks, cols):
        n, F, P = Psi.shape
        M = mono.shape[-1]
        PM = np.empty((F, P, n * (M + 1)))
        for k in range(n):
            PM[:, :, n * M + k] = Psi[k]
            if M:
                np.multiply(mono[k], Psi[k][:, :, None], out=PM[:, :, k * M:(k + 1) * M])
        start = np.where(sel >= 0, indptr[np.maximum(sel, 0)], nnz)
        for c in np.unique(cnt).tolist():
            g = np.flatnonzero(cnt == c)
            G = len(g)
            gi = np.arange(G)
            posg = np.minimum(pos[g], c)  # padding ids -> one scratch column c
            C = np.zeros((G, n * (M + 1), c + 1))
            for k in range(n):
                pk = posg[:, k * K:(k + 1) * K]  # local columns of [u_k, N_{u_k}]
                C[gi, n * M + k, pk[:, 0]] = 1.0  # the constant X_u
                if M:
                    A = coef[u[k, g]]  # (G, M, N); padding columns are 0
                    rows = k * M + np.arange(M)
                    C[gi[:, None, None], rows[None, :, None], pk[:, None, 1:]] = A
                    C[gi[:, None], rows[None, :], pk[:, :1]] -= A.sum(axis=2)
            dest = start[g][:, :, None] + np.arange(c)
            data[dest] = np.matmul(PM[g], C[:, :, :c])  # (G, P, c)
            indices[dest] = L[g, None, :c]
    return sp.csr_matrix((data[:nnz], indices[:nnz], indptr), shape=(n_points, n_vertices))
