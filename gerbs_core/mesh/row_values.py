"""The candidate local functions at the energies' sample-corner rows (the choice of
:mod:`gerbs_core.mesh.agreement`): values and derivatives as sparse row products, in
cache-sized chunks of rows.

A row s (a sample and a corner of its face, vertex v) holds per-row monomial values
B[s] (M,); a candidate's value there is sum_m B[s, m] c_{v M + m}: one csr (SC, V M)
product with the coefficients, which every candidate with M coefficients shares.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .monomials import n_monomials

__all__ = ["CHUNK_ROWS", "row_matrix", "rows_apply", "candidate_coefs", "own_rows",
           "copy_aliases", "per_degree", "row_sums", "square_norms", "chunks",
           "candidate_values"]

CHUNK_ROWS = 8192             # rows per chunk of the energies' row-by-row work


def row_matrix(B, vertex, V):
    """csr (SC, V M) with row s holding B[s] (SC, M) in the columns vertex[s] M + m: the
    sample rows' local functions as one sparse product with coefficients (V M, k)."""
    SC, M = B.shape
    it = np.int32 if V * M < 2 ** 31 - 1 else np.int64      # scipy's own index type
    cols = (vertex.astype(it)[:, None] * it(M) + np.arange(M, dtype=it)).ravel()
    return sp.csr_matrix((np.ascontiguousarray(B).ravel(), cols,
                          np.arange(0, SC * M + 1, M, dtype=it)), shape=(SC, V * M))


def rows_apply(B, vertex, coef):
    """sum_m B[s, m] coef[vertex[s] M + m] (SC, 3) for per-row monomial values B (SC, M) and
    coefficients coef (V M, 3): one sparse product (no (SC, M, 3) temporaries)."""
    return row_matrix(B, vertex, coef.shape[0] // B.shape[1]) @ coef


def candidate_coefs(cands, X):
    """Every candidate's coefficients (V M, 3) at positions X: computed once for the fold
    penalty and the choice."""
    return [(c.matrix @ X).reshape(-1, 3) for c in cands]


def own_rows(cand, vertex):
    """None (every row), or the rows (indices into vertex) of the vertices where the
    candidate is its own fit -- elsewhere it is another candidate's bit for bit
    (:attr:`~gerbs_core.mesh.fits.CandidateFits.alias`), whose values it takes."""
    return None if cand.alias is None else np.flatnonzero(~cand.alias[1][vertex])


def copy_aliases(out, cands, vertex):
    """out (SC, ncand, ...) with each aliased candidate's entries at the rows of the
    vertices it shares with its source j copied from j's: the values its own evaluation
    would give there, bit for bit (the same coefficients through the same arithmetic)."""
    for i, c in enumerate(cands):
        if c.alias is not None:
            j, same = c.alias
            r = same[vertex]
            out[r, i] = out[r, j]
    return out


def per_degree(cands, coefs, B, vertex):
    """Yields (i, own, values) for every candidate i, M its coefficient count: own None and
    values = rows_apply(B[:, :M], vertex, coefs[i]) (one row matrix serves all candidates
    of a size), or, for an aliased candidate, own its own rows (:func:`own_rows`) and the
    values there only (none: not yielded); :func:`copy_aliases` fills the rest."""
    V = cands[0].matrix.shape[1]
    sizes = [n_monomials(c.degree) for c in cands]
    for M in sorted(set(sizes)):
        rows = None
        for i in np.flatnonzero(np.array(sizes) == M).tolist():
            own = own_rows(cands[i], vertex)
            if own is None:
                rows = row_matrix(B[:, :M], vertex, V) if rows is None else rows
                yield i, None, rows @ coefs[i]
            elif len(own):
                yield i, own, row_matrix(B[own, :M], vertex[own], V) @ coefs[i]


def row_sums(w):
    """w (..., n) summed over its last axis, bit for bit ``w.sum(-1)``: below 8 terms numpy
    adds them in order, ((w0 + w1) + w2) + ..., done here column by column without its slow
    reduction over a short axis (measured 2-4x); from 8 on (pairwise sums) numpy's own."""
    n = w.shape[-1]
    if n >= 8 or n == 0:
        return w.sum(-1)
    out = w[..., 0] + 0.0       # numpy's sum starts from +0.0: a row of -0.0 sums to +0.0
    for k in range(1, n):
        out += w[..., k]
    return out


def square_norms(d):
    """|d|^2 (...) over the last axis of d (..., n): bit for bit ``(d ** 2).sum(-1)``
    (:func:`row_sums`)."""
    return row_sums(d * d)


def chunks(n):
    """Slices of CHUNK_ROWS of n rows (sample-corner rows, or samples): row-by-row work in
    cache-sized pieces (measured: whole arrays made the fold penalty's time per row 2x
    larger on a 128x128 grid than on a 64x64 one)."""
    return [slice(s, min(n, s + CHUNK_ROWS)) for s in range(0, n, CHUNK_ROWS)]


def candidate_values(cands, X, vertex, Bu, coefs=None):
    """Values (SC, ncand, 3) of every candidate local function at the sample corners."""
    coefs = candidate_coefs(cands, X) if coefs is None else coefs
    out = np.empty((len(vertex), len(cands), 3))
    for sl in chunks(len(vertex)):
        Xs = X[vertex[sl]]
        for i, own, v in per_degree(cands, coefs, Bu[sl], vertex[sl]):
            if own is None:
                out[sl, i] = Xs + v
            else:
                out[sl, i][own] = Xs[own] + v
        copy_aliases(out[sl], cands, vertex[sl])
    return out
