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

from functools import lru_cache

import numpy as np
import scipy.sparse as sp

from .arrays import ranges
from .monomials import bending_gram, monomial_exponents, monomials, n_monomials

__all__ = ["RCOND", "CANDIDATES", "pinned_normal_inverse", "candidate_fits",
           "candidate_fits_all", "CandidateFits", "shared_rows",
           "chosen_rows"]

# relative eigenvalue cut-off of the normal matrices (in the bending metric, scaled
# coordinates y / h): a normal-matrix eigenvalue of 1e-8 is a singular value of 1e-4 of
# the weighted design, the conditioning below which a fit follows round-off or noise
RCOND = 1e-8

# the normal-matrix condition beyond which a ring-1 fit takes ring 2 too (the original
# design's design-matrix limit of ~100, squared)
MAX_CONDITION = 1e4

# the candidate rules (degree, data rings) each vertex chooses from (mesh.agreement)
CANDIDATES = ((2, 1), (3, 1), (3, 2), (4, 2))

# data (vertices x padded data count) per chunk of the batched fits
CHUNK_DATA = 16_384


@lru_cache(maxsize=None)
def _probe(n: int) -> np.ndarray:
    """A fixed random vector (n,): the grouping key of :func:`shared_rows`."""
    return np.random.default_rng(0).uniform(0.5, 1.5, n)


def shared_rows(N: np.ndarray, fn):
    """fn(N) for a batch N (K, ...) with fn row by row, evaluated once per distinct row:
    rows equal bit for bit (stars of the same shape: a grid's interior, an icosphere's
    symmetric vertices) share one evaluation, so the result is fn(N)'s exactly. Rows are
    grouped by a random projection and each kept in its group only if it equals the
    group's first row, so a key collision costs an evaluation, never a wrong result."""
    K = len(N)
    if K < 2:
        return fn(N)
    flat = N.reshape(K, -1)
    _, first, inv = np.unique(flat @ _probe(flat.shape[1]), return_index=True, return_inverse=True)
    rep = first[inv.ravel()]
    rep = np.where(np.all(flat == flat[rep], axis=1), rep, np.arange(K))
    distinct, back = np.unique(rep, return_inverse=True)
    if len(distinct) == K:
        return fn(N)
    return fn(N[distinct])[back.ravel()]


def pinned_normal_inverse(N: np.ndarray, degree: int, certified: bool = False) -> np.ndarray:
    """Truncated pseudo-inverses (K, M, M) of normal matrices N (K, M, M) of scaled-monomial
    fits, in the bending metric: c = P @ (B^T W t) is the smoothest minimiser. Equal
    matrices are factored once (:func:`shared_rows`). ``certified``: where a Cholesky
    factorization certifies that no eigenvalue is truncated, the plain inverse from it
    (:func:`_certified_inverse`: the same matrix to rounding, ~3x faster than the
    eigendecomposition), the eigendecomposition elsewhere."""
    fn = _certified_pinned_inverse if certified else _pinned_normal_inverse
    return shared_rows(np.asarray(N, dtype=np.float64), lambda Nd: fn(Nd, degree))


# the certified inverse's bound on the condition (in the bending metric): far below 1 / RCOND
# (no eigenvalue near the truncation), and small enough that it and the eigendecomposition's
# inverse agree to rounding (measured: 1e-12 relative on Suzanne's coupled fits)
CERTIFIED_CONDITION = 1e6


@lru_cache(maxsize=None)
def _gram_inverse_factor(degree: int) -> np.ndarray:
    """L^-1 (M, M) with G = L L^T the bending Gram matrix: coordinates z = L^T c."""
    arr = np.linalg.inv(np.linalg.cholesky(bending_gram(degree)))
    arr.flags.writeable = False
    return arr


def _pinned_normal_inverse(N: np.ndarray, degree: int) -> np.ndarray:
    Li = _gram_inverse_factor(degree)
    Nz = Li @ N @ Li.T
    lam, Q = np.linalg.eigh(Nz)
    top = lam[..., -1:]
    inv = np.where(lam > RCOND * np.maximum(top, 1e-300), 1.0 / np.where(lam > 0, lam, 1.0), 0.0)
    Pz = (Q * inv[..., None, :]) @ np.swapaxes(Q, -1, -2)
    return Li.T @ Pz @ Li


def _certified_inverse(Nz: np.ndarray):
    """(Nz^-1 (K, M, M), certified (K,) bool) for symmetric Nz (K, M, M) from Cholesky
    factors Nz = Lz Lz^T: with Lzi = Lz^-1, Nz^-1 = Lzi^T Lzi and trace(Nz) trace(Nz^-1)
    >= lam_max / lam_min, so a product below CERTIFIED_CONDITION certifies that the
    truncated pseudo-inverse truncates nothing: it is this inverse. None when some matrix
    is not positive definite (numpy factors the stack at once)."""
    try:
        Lz = np.linalg.cholesky(Nz)
    except np.linalg.LinAlgError:
        return None
    Lzi = np.linalg.inv(Lz)
    bound = np.trace(Nz, axis1=1, axis2=2) * (Lzi * Lzi).sum(axis=(1, 2))
    return Lzi, bound < CERTIFIED_CONDITION


def _certified_pinned_inverse(N: np.ndarray, degree: int) -> np.ndarray:
    """:func:`_pinned_normal_inverse` to rounding, from Cholesky factors where they certify
    that no eigenvalue is truncated (the others by the eigendecomposition)."""
    Li = _gram_inverse_factor(degree)
    got = _certified_inverse(Li @ N @ Li.T) if len(N) else None
    if got is None:
        return _pinned_normal_inverse(N, degree)
    Lzi, ok = got
    T = Lzi @ Li                                 # P = Li^T Nz^-1 Li = T^T T
    out = np.swapaxes(T, -1, -2) @ T
    if not ok.all():
        bad = np.flatnonzero(~ok)
        out[bad] = _pinned_normal_inverse(N[bad], degree)
    return out


class CandidateFits:
    """The data fits of one rule for all vertices: coefficients c_v = A_v (X_N - X_v).

    ``degree``; ``matrix`` (V*M, V) sparse, rows v*M + m: the coefficient operator in
    UNSCALED chart coordinates (pin included: c = matrix @ X). ``normal`` (V, M, M):
    the data normal matrices in scaled coordinates y / h_v (for the coupled fits of
    :mod:`gerbs_core.mesh.agreement`), ``rhs`` (V*M, V) sparse: their right-hand sides.
    ``alias``: None, or (j, same (V,) bool): at the vertices ``same`` this fit is
    candidate j's (same degree) bit for bit -- rows, right-hand sides and normal matrices
    -- so the choice need not evaluate it there (a ring-1 rule fallen back to two layers).
    """

    def __init__(self, degree, matrix, normal, rhs, alias=None):
        self.degree, self.matrix, self.normal, self.rhs = degree, matrix, normal, rhs
        self.alias = alias


def _data_weights(y, use, inverse_square=None):
    """1 / |y|^2 for scaled chart positions y (h = 1) of the data used, 0 elsewhere: near
    data count more (the fit is used near its vertex). ``inverse_square``: the weights of
    all data (:func:`_inverse_squares` of y), when several rules weigh the same y."""
    q = _inverse_squares(y) if inverse_square is None else inverse_square
    return np.where(use, q, 0.0)


def _inverse_squares(y):
    """1 / |y|^2 (0 at y = 0) of scaled chart positions y (..., 2)."""
    d = np.hypot(y[..., 0], y[..., 1])
    return np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0) ** 2, 0.0)


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
    acc = [{"normal": np.zeros((V, n_monomials(d), n_monomials(d))), "blocks": [],
            "alias": np.zeros(V, dtype=bool)} for d, _ in rules]
    # batches of equal padded length (powers of two): little padding for high valences;
    # in chunks of vertices whose working set stays in cache (measured: whole batches made
    # the time per vertex grow 1.4x from a 64x64 to a 128x128 grid)
    pad = 2 ** np.ceil(np.log2(np.maximum(cnt, 1))).astype(np.int64)
    for n in np.unique(pad).tolist():
        batch = np.flatnonzero(pad == n)
        step = max(1, CHUNK_DATA // n)
        for c0 in range(0, len(batch), step):
            _fit_chunk(rings, rules, acc, batch[c0:c0 + step], n, cnt, n1, n2, wider, dmax)
    mats = [_block_rows(a["blocks"], V, n_monomials(d)) for (d, _), a in zip(rules, acc)]
    for i, ((degree, _), a) in enumerate(zip(rules, acc)):
        alias = None
        if a["alias"].any():
            alias = (rules.index((degree, 2)), a["alias"])
            mats[i] = _merged_rows(mats[alias[0]], mats[i], a["alias"], degree, V)
        out.append(CandidateFits(degree, mats[i][0], a["normal"], mats[i][1], alias))
    return out


def _merged_rows(wide, own, same, degree, V):
    """(matrix, rhs) of an aliased rule: the rows of the (d, 2) rule's ``wide`` (matrix,
    rhs) at the vertices ``same`` (V,), its ``own`` rows elsewhere, copied as they are
    (:func:`chosen_rows`): the entries its blocks would have given, row by row (scipy
    sorts and sums each row's coordinates by itself). All aliased: wide's matrices."""
    if same.all():
        return wide
    pair = [CandidateFits(degree, m, None, r) for m, r in (wide, own)]
    pick = np.where(same, 0, 1)
    M = n_monomials(degree)
    return tuple(chosen_rows(pair, pick, part, V, M) for part in ("matrix", "rhs"))


def _fit_chunk(rings, rules, acc, vs, n, cnt, n1, n2, wider, dmax):
    """The fits of the vertices vs (K,), padded to n data, for every rule: normal matrices
    into acc[rule]["normal"], operator blocks appended to acc[rule]["blocks"]; a ring-1
    rule (d, 1) with (d, 2) a rule too gets acc[rule]["alias"][v] where v falls back to two
    layers: its fit is the (d, 2) fit there (the same data, weights and arithmetic), whose
    normals and rows (:func:`_merged_rows`) it takes instead of computing them again."""
    k = np.arange(n)[None, :]
    idx = rings.offsets[vs][:, None] + np.minimum(k, cnt[vs][:, None] - 1)
    real = k < cnt[vs][:, None]
    ring = rings.ring[idx]
    y = rings.y[idx] / rings.h[vs][:, None, None]
    h = rings.h[vs]
    Ball = monomials(y, dmax)[0]                          # (K, n, M_max)
    iq = _inverse_squares(y)                              # every rule's data weights
    q = rings.ids[idx]
    done = {}                                             # (d, 2) -> its normal matrices
    # the wider rules first, so that a ring-1 rule's fallback can take theirs
    for j in sorted(range(len(rules)), key=lambda j: -rules[j][1]):
        (degree, layers), a = rules[j], acc[j]
        M = n_monomials(degree)
        B = Ball[..., :M]
        use_layers = np.full(len(vs), layers)
        if layers < 2:
            # the condition only where ring 1 holds enough data (else ring 2 is taken anyway)
            s = np.flatnonzero(n1[vs] >= M + 2)
            N1 = _normal(B[s], _data_weights(y[s], real[s] & (ring[s] <= 1), iq[s]))
            lam = shared_rows(N1, np.linalg.eigvalsh)
            cond = lam[:, -1] / np.maximum(lam[:, 0], 1e-300)
            use_layers[:] = 2
            use_layers[s[~(cond > MAX_CONDITION)]] = layers
        wide = done.get((degree, 2)) if layers < 2 else None
        if wide is not None and np.any(use_layers == 2):
            # the fallen-back vertices' rows are the (d, 2) fit's: blocks of the others only
            a["alias"][vs] = use_layers == 2
            a["normal"][vs] = wide
            own = np.flatnonzero(use_layers < 2)
            if len(own):
                use, N, A, bw = _fit(y[own], B[own], real[own] & (ring[own] <= layers),
                                     h[own], degree, iq[own])
                a["normal"][vs[own]] = N
                a["blocks"].append(_compact(vs[own], use, q[own], A, bw))
            continue
        use_layers = np.where((use_layers == 2) & (n2[vs] < M + 2), wider, use_layers)
        use, N, A, bw = _fit(y, B, real & (ring <= use_layers[:, None]), h, degree, iq)
        a["normal"][vs] = N
        a["blocks"].append(_compact(vs, use, q, A, bw))   # A, bw: zero off the used data
        if layers == 2:
            done[(degree, layers)] = N


def _fit(y, B, use, h, degree, inverse_square=None):
    """(use, N (K, M, M), A (K, M, n), bw (K, M, n)) of the fits of the data ``use`` (K, n)
    at scaled chart positions y (K, n, 2), designs B (K, n, M), chart scales h (K,):
    normal matrices, the unscaled operators (A, zero off the used data) and the
    weighted designs (the normal equations' right-hand sides). ``inverse_square``: the
    chunk's 1 / |y|^2 (:func:`_inverse_squares`, shared by its rules) if made already."""
    w = _data_weights(y, use, inverse_square)
    w /= np.maximum(w.sum(1, keepdims=True), 1e-300)      # per vertex: weights sum to 1
    bw = np.swapaxes(B * w[..., None], 1, 2)              # (K, M, n)
    N = bw @ B
    Pinv = pinned_normal_inverse(N, degree)
    deg_of = monomial_exponents(degree).sum(1)
    A = (Pinv @ bw) / h[:, None, None] ** deg_of[None, :, None]  # unscaled
    return use, N, A, bw


def _compact(vs, use, q, A, bw):
    """One chunk's csr rows: vertex k's rows hold the used data ids q (K, n) and the pin
    (column v, minus the row's sum) with the operator values A and the right-hand-side
    values bw (K, M, n; zero off the used data). Compact form (vs, cols (K, r), nr (K,),
    rank (K, n + 1), A, bw) -- vertex k's nr[k] columns by increasing column (all rows of
    a vertex share its columns), rank[k, j] the slot of its data j (j = n: the pin), the
    unused data ranked at nr[k] or later -- when no vertex is reached by several
    unfoldings (grids, flat meshes); else coordinates (rows, cols, vals, hvals), data
    then pins, for scipy to sort and sum."""
    V = np.iinfo(np.int64).max
    cols = np.concatenate([np.where(use, q, V), vs[:, None]], axis=1)  # unused: last
    order = np.argsort(cols, axis=1, kind="stable")
    cols = np.take_along_axis(cols, order, axis=1)
    if np.any((cols[:, 1:] == cols[:, :-1]) & (cols[:, 1:] < V)):
        return _coo_rows(vs, use, q, A, bw)
    nr = (cols < V).sum(1)
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.arange(order.shape[1]), axis=1)
    return vs, cols[:, :int(nr.max())], nr, rank, A, bw


def _coo_rows(vs, use, q, A, bw):
    """A chunk's rows as coordinates (rows, cols, vals, hvals): the used data, then the
    pins."""
    K, M, _ = A.shape
    kk, nn = np.nonzero(use)
    r = vs[:, None] * M + np.arange(M)
    return (np.concatenate([r[kk].ravel(), r.ravel()]),
            np.concatenate([np.repeat(q[kk, nn], M), np.repeat(vs, M)]),
            np.concatenate([A[kk, :, nn].ravel(), -A.sum(2).ravel()]),
            np.concatenate([bw[kk, :, nn].ravel(), -bw.sum(2).ravel()]))


def _block_rows(blocks, V, M):
    """The operator and right-hand-side csr matrices (V M, V), canonical, from the chunks'
    rows (:func:`_compact`): the compact chunks' rows -- their lengths known -- with every
    value scattered once from A and bw straight to its csr slot; the other chunks' rows
    (a vertex reached by several unfoldings) as coordinates, sorted and summed by scipy,
    and copied into their slots. Every row is one vertex's, from one chunk: the entries
    are those of sorting and summing all chunks' coordinates together (scipy sorts and
    sums row by row), bit for bit. Measured on a 35k-vertex triangulated height field with
    a boundary, where 2 of its 35 chunks are not compact: 3.1 -> 0.4 s for its rules."""
    compact = [b for b in blocks if len(b) == 6]
    coords = [b for b in blocks if len(b) == 4]
    shape = (V * M, V)
    other = None
    if coords:
        rows, cols = (np.concatenate([p[i] for p in coords]) for i in (0, 1))
        other = tuple(sp.csr_matrix((np.concatenate([p[i] for p in coords]), (rows, cols)),
                                    shape=shape) for i in (2, 3))
        if not compact:
            return other
    nrow = np.zeros(V, dtype=np.int64)
    for vs, _, nr, _, _, _ in compact:
        nrow[vs] = nr
    lens = np.repeat(nrow, M)
    if other is not None:
        lens += np.diff(other[0].indptr)
    indptr = np.zeros(V * M + 1, dtype=np.int64)
    np.cumsum(lens, out=indptr[1:])
    nnz = int(indptr[-1])
    indices = np.empty(nnz, dtype=np.int32 if V < 2 ** 31 - 1 else np.int64)
    out = [np.empty(nnz + 1), np.empty(nnz + 1)]          # + the spare slot
    for vs, cols, nr, rank, A, bw in compact:
        r = cols.shape[1]
        start = indptr[:-1][vs[:, None] * M + np.arange(M)]           # (K, M)
        slot = np.where(rank < nr[:, None], rank, nnz)                # (K, n + 1)
        pos = np.where(slot[:, None, :] < nnz, start[:, :, None] + slot[:, None, :], nnz)
        for o, X in zip(out, (A, bw)):
            o[pos[:, :, :-1]] = X
            o[pos[:, :, -1]] = -X.sum(2)
        # the columns: each row's r slots (those below nr real)
        cpos = start[:, :, None] + np.arange(r)
        ok = np.broadcast_to((np.arange(r) < nr[:, None])[:, None, :], cpos.shape)
        c = np.broadcast_to(cols[:, None, :], cpos.shape)
        if ok.all():
            indices[cpos.ravel()] = c.ravel()
        else:
            indices[cpos[ok]] = c[ok]
    if other is not None:  # the coordinate chunks' rows, as scipy made them
        lo = np.diff(other[0].indptr)
        r = np.flatnonzero(lo)
        to, fr = ranges(indptr[r], lo[r]), ranges(other[0].indptr[r], lo[r])
        indices[to] = other[0].indices[fr]
        for o, m in zip(out, other):
            o[to] = m.data[fr]
    mats = (sp.csr_matrix((out[0][:nnz], indices, indptr), shape=shape),
            sp.csr_matrix((out[1][:nnz], indices.copy(), indptr.copy()), shape=shape))
    for m in mats:
        m.has_canonical_format = True
    return mats


def _data_ids(block):
    """The data ids (K, n) of a compact chunk (:func:`_compact`), from its sorted columns
    and ranks (the unused data: any id, they are masked)."""
    _, cols, nr, rank, _, _ = block
    return np.take_along_axis(cols, np.minimum(rank[:, :-1], cols.shape[1] - 1), axis=1)


def _canonical(A):
    """A as canonical csr (sorted, duplicates summed; a product's rows may come unsorted),
    the caller's matrix untouched."""
    A = A.tocsr()
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
    return A


def chosen_rows(cands, choice, part, V, mmax):
    """csr (V mmax, V): rows v mmax + m (m < M) are row v M + m of the ``part`` ("matrix"
    or "rhs") of vertex v's chosen candidate cands[choice[v]] (the padded layout of the
    coefficients, :mod:`gerbs_core.mesh.agreement`), the others empty. The candidates'
    canonical rows are copied as they are, straight into the output arrays (the same
    entries in the same order as a coordinate-format selection would give)."""
    mats = [_canonical(getattr(c, part)) for c in cands]
    m = np.tile(np.arange(mmax), V)
    v = np.repeat(np.arange(V), mmax)
    pick = np.repeat(choice, mmax)
    lens = np.zeros(V * mmax, dtype=np.int64)
    src = []
    for i, (A, c) in enumerate(zip(mats, cands)):
        M = n_monomials(c.degree)
        rows = np.flatnonzero((pick == i) & (m < M))
        r = v[rows] * M + m[rows]
        lens[rows] = A.indptr[r + 1] - A.indptr[r]
        src.append((rows, r))
    indptr = np.zeros(V * mmax + 1, dtype=np.int64)
    np.cumsum(lens, out=indptr[1:])
    data = np.empty(indptr[-1])
    indices = np.empty(indptr[-1], dtype=mats[0].indices.dtype)
    for A, (rows, r) in zip(mats, src):
        cnt = lens[rows]
        to, fr = ranges(indptr[rows], cnt), ranges(A.indptr[r], cnt)
        data[to], indices[to] = A.data[fr], A.indices[fr]
    return sp.csr_matrix((data, indices, indptr), shape=(V * mmax, V))
