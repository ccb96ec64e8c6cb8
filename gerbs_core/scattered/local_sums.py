"""The interpolant's sum f = sum_k B_k T_k at query points, from the basis jets and the
local Taylor polynomials' monomial coefficients (:func:`~.taylor.coefficient_tables`).

One query chunk: B (M, K) (and gradient / Hessian), the candidates' point indices
j (M, K), and the monomials of the offsets x - x_j as (Q, K, M) rows
(:func:`~.taylor.monomials` of the (K, M) coordinate arrays).
"""
from __future__ import annotations

import numpy as np

__all__ = ["blend_sum"]


def blend_sum(nu, Bv, Bg, Bh, C, CT, j, jt, mono):
    """sum_k B_k T_k and its derivatives: (M, V) for nu = 0, (M, V, n) for nu = 1,
    (M, V, n, n) for nu = 2 (the Leibniz rule on the product).

    C: [C0 (N, V, Q), C1, C2][: nu + 1]; CT: C0 as (Q, N, V) (or None); j (M, K) and
    jt = j.T contiguous; mono (Q, K, M); Bv finite (zeros at empty slots).
    """
    if nu == 0 and C[0].shape[1] == 1 and CT is not None:
        return _values_scalar(Bv, CT, jt, mono)
    # (M, K, Q) rows: einsum's summation order (its last bits) follows the layout
    mono = np.ascontiguousarray(mono.transpose(2, 1, 0))
    if nu == 0:
        return np.einsum("mk,mkvq,mkq->mv", Bv, C[0][j], mono)
    Tv = np.einsum("mkvq,mkq->mkv", C[0][j], mono)
    Tg = np.einsum("mkvlq,mkq->mkvl", C[1][j], mono[..., : C[1].shape[-1]])
    if nu == 1:
        return np.einsum("mki,mkv->mvi", Bg, Tv) + np.einsum("mk,mkvi->mvi", Bv, Tg)
    Th = np.einsum("mkvlrq,mkq->mkvlr", C[2][j], mono[..., : C[2].shape[-1]])
    return (np.einsum("mkij,mkv->mvij", Bh, Tv) + np.einsum("mki,mkvj->mvij", Bg, Tg)
            + np.einsum("mkj,mkvi->mvij", Bg, Tg) + np.einsum("mk,mkvij->mvij", Bv, Th))


def _values_scalar(Bv, CT, jt, mono):
    """sum_k B[m, k] sum_q C[j[m, k], q] mono[q, k, m] for one value (V = 1), term by
    term into one accumulator: the same bits as einsum("mk,mkvq,mkq->mv"), which
    runs over k, then q, adding (B C) mono to a zero start (tests/core/test_hermite.py
    compares), without its gather of C (M, K, 1, Q): 2x faster on 20,000 x 3 queries."""
    Q, K, M = mono.shape
    acc = np.zeros((M, 1))
    tmp = np.empty((M, 1))
    Bt = np.ascontiguousarray(Bv.T)
    for k in range(K):
        b, jk = Bt[k][:, None], jt[k]
        for q in range(Q):
            np.take(CT[q], jk, axis=0, out=tmp)
            tmp *= b
            tmp *= mono[q, k][:, None]
            acc += tmp
    return acc
