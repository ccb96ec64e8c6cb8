"""The coupled fits (step 2 of the fair-shape rule, :mod:`gerbs_core.mesh.agreement`) as a
linear map of the positions.

Starting from the chosen data fits c_0 = C X, every sweep solves, vertex by vertex with
its neighbours' current coefficients frozen (damped block Jacobi),

    (N_data + mu B^T W_a B + lam B^T W_t B) c_v = r_data + r_tension + r_agreement(c),

on the energies' sample-corner rows (sample p, vertex v, weight w, Psi = P):

    r_tension   = B^T [w_t (cage(p) - X_v)],                      w_t = lam w s P,
    r_agreement = B^T [mu w P (T(p) - P l_v(p)) - w_a X_v],        w_a = mu w P (1 - P),

with l_v(p) = X_v + B_v(p) . c_v and T(p) = sum over the sample's corners of P l. Every
step is a product with a sparse matrix fixed by the rest shape, so the coefficients are
linear in X: :class:`CoupledFits` applies the map to positions (a few sparse products
with k = 3 columns: what a build needs) and makes the explicit operator (V MMAX, V) only
when asked (:attr:`CoupledFits.operator`: stencil updates and locality tests), by
applying the SAME map to the identity.
"""
from __future__ import annotations

from functools import cached_property

import numpy as np
import scipy.sparse as sp

from .coupling_local import local_parts, neighbourhood, vertex_graph
from .fits import pinned_normal_inverse
from .monomials import monomial_exponents, n_monomials
from .selection import selection_matrix

__all__ = ["CoupledFits", "SelectedFits", "coupled_fits", "identity_fits", "zero_row_sums",
           "LOCAL_REACH"]

# hops in the data-fit graph (each up to 2 rings) around moved vertices within which a
# column of the map and all its intermediates lie, with a margin: data fit 1 hop, each
# of the (2) sweeps at most 1 more, the margin 1 (tested against the operator)
LOCAL_REACH = 4


class CoupledFits:
    """Coefficients of the local functions as a fixed linear map of the positions.

    ``fits(X)`` -> (V MMAX, k) for positions X (V, k) (rows v MMAX + m, unscaled chart
    coordinates); :attr:`operator` the same map as a csr matrix (V MMAX, V), built on
    first use, whose rows sum to 0 exactly (translations move every local function
    rigidly). Immutable.
    """

    def __init__(self, chosen, sweeps=0, damping=1.0, parts=None, projection=None):
        self.chosen = chosen.tocsr()
        self.sweeps = int(sweeps) if parts is not None else 0
        self.damping = float(damping)
        self._parts = parts
        self._projection = projection   # crease curve constraints (R, K, G) or None
        self.shape = self.chosen.shape
        self._last = None     # (key, columns): memo of the last columns() request

    def __call__(self, X):
        """Coefficients (V MMAX, k) for positions X (V, k) or (V,)."""
        X = np.asarray(X, dtype=np.float64)
        # constants have zero coefficients (the pin carries them): take off each row's
        # response to constants times its own vertex's position, as the row-sum correction
        # of `operator` does, so that the round-off of ill-conditioned fits cannot show as
        # W @ 1 != 1; row i's correction reads only its own vertex (locality is kept)
        if "_constant_response" not in self.__dict__:
            # the first call maps X and the constants together (one pass over the matrices;
            # every column's sums are the same as alone)
            both = self._map(np.column_stack([X.reshape(len(X), -1), np.ones(len(X))]))
            self.__dict__["_constant_response"] = both[:, -1].copy()
            mapped = both[:, :-1].reshape((-1,) + X.shape[1:])
        else:
            mapped = self._map(X)
        r = self._constant_response
        own = X[np.arange(len(r)) // (len(r) // self.shape[1])]
        return mapped - (r * own if X.ndim == 1 else r[:, None] * own)

    @cached_property
    def _constant_response(self) -> np.ndarray:
        """The map applied to constants (V MMAX,): zero but for round-off."""
        return self._map(np.ones(self.shape[1]))

    def _map(self, Y):
        """The map applied to Y: a dense (V, k) array, or a sparse (V, V) matrix."""
        return _apply(self.chosen, self._parts, self.sweeps, self.damping, Y, self._projection)

    @cached_property
    def operator(self) -> sp.csr_matrix:
        """The explicit operator (V MMAX, V) (csr; rows summing to 0 exactly)."""
        # constants have zero coefficients (the pin carries them): every row sums to 0
        # exactly, whatever the round-off of ill-conditioned fits (it would show as W @ 1 != 1)
        return zero_row_sums(sp.csr_matrix(self._map(sp.identity(self.shape[1], format="csr"))))

    def columns(self, cols) -> sp.csc_matrix:
        """Columns ``cols`` (m,) of :attr:`operator` as a csc (V MMAX, m), without making
        the operator: the map applied to those unit vectors on a neighbourhood of them
        (:mod:`gerbs_core.mesh.coupling_local`: cost ~ the neighbourhood, not the mesh),
        with the same row-sum correction (to round-off). The last request is memoized
        (a drag moves the same vertices frame after frame)."""
        cols = np.asarray(cols, dtype=np.int64).ravel()
        key = cols.tobytes()
        if self._last is not None and self._last[0] == key:
            return self._last[1]
        if self.operator_built:
            out = self.operator.tocsc()[:, cols]
        else:
            out = self._columns(cols)
        self._last = (key, out)
        return out

    def _columns(self, cols):
        V, m = self.shape[1], len(cols)
        mmax = self.shape[0] // V
        verts = (neighbourhood(self._graph, cols, LOCAL_REACH) if self.sweeps
                 else np.arange(V))
        # most of the mesh, or crease constraints (global rows): the map itself
        if len(verts) > V // 2 or self._projection is not None:
            chosen, parts, R, verts = self.chosen, self._parts, np.arange(V * mmax), np.arange(V)
        else:
            chosen, parts, R = local_parts(self.chosen, self._parts, verts, mmax,
                                           self._owner)
        at = np.searchsorted(verts, cols)
        unit = sp.csr_matrix((np.ones(m), (at, np.arange(m))), shape=(len(verts), m))
        pr = self._projection
        local = sp.csr_matrix(_apply(chosen, parts, self.sweeps, self.damping, unit, pr))
        # minus the row sums of the moved vertices' own rows, in their columns: the same
        # correction as the operator's (these rows' supports lie inside the neighbourhood)
        sums = _apply(chosen, parts, self.sweeps, self.damping, np.ones((len(verts), 1)),
                      pr)[:, 0]
        own = np.flatnonzero(np.isin(R // mmax, cols))
        where = np.argsort(cols)[np.searchsorted(np.sort(cols), R[own] // mmax)]
        local = local - sp.csr_matrix((sums[own], (own, where)), shape=local.shape)
        lc = local.tocoo()
        out = sp.csc_matrix((lc.data, (R[lc.row], lc.col)), shape=(self.shape[0], m))
        out.eliminate_zeros()
        return out

    @cached_property
    def _graph(self):
        return vertex_graph(self.chosen, self.shape[1])

    @cached_property
    def _owner(self):
        """Per vertex its sample-corner rows (csc of the rows' vertex incidence)."""
        return self._parts["rows"].tocsc()

    @property
    def operator_built(self) -> bool:
        return "operator" in self.__dict__


def zero_row_sums(op) -> sp.csr_matrix:
    """A coefficient operator (V MMAX, V) with each row's sum taken off at its own vertex's
    column (row i belongs to vertex i // MMAX): rows summing to 0 (constants have zero
    coefficients), canonical csr."""
    op = sp.csr_matrix(op)
    n = op.shape[0]
    rows = np.arange(n)
    op = op - sp.csr_matrix((np.asarray(op.sum(axis=1)).ravel(), (rows, rows // (n // op.shape[1]))),
                            shape=op.shape)
    op.sum_duplicates()
    op.eliminate_zeros()
    return op


def _project(proj, c, Y):
    """The linear constraints (crease curves, :mod:`gerbs_core.mesh.crease_fits`), if any:
    c - R (K c - G Y)."""
    if proj is None:
        return c
    R, K, G = proj
    c = c - R @ (K @ c - G @ Y)
    if sp.issparse(c):
        c = c.tocsr()
        c.eliminate_zeros()
    return c


def _sum(a, fresh):
    """a + fresh; dense: added into ``fresh`` (a product made for it; IEEE addition is
    commutative: the same bits). Sparse: ``a + fresh`` as written (the entries' order of
    the result follows the operands')."""
    if sp.issparse(fresh) or sp.issparse(a):
        return a + fresh
    fresh += a
    return fresh


def _diff(fresh, b):
    """fresh - b; dense: in place in ``fresh`` (a product made for it)."""
    if sp.issparse(fresh) or sp.issparse(b):
        return fresh - b
    fresh -= b
    return fresh


def _apply(chosen, p, sweeps, d, Y, proj=None):
    """The map (module docstring) with matrices ``chosen``, ``p`` applied to Y; ``proj``
    the crease constraints, imposed after the first fit and every sweep."""
    c = _project(proj, chosen @ Y, Y)
    if not sweeps:
        return c
    # (dense Y: the sums and differences written into the fresh products, the same values
    # as the expressions in the comments, with fewer (SC, k) arrays alive at once)
    Xs = p["rows"] @ Y                                   # X_v of every row
    # fixed = rhs Y + BsT (Wt (cage Y - Xs) - Wa Xs)
    fixed = p["BsT"] @ _diff(p["Wt"] @ _diff(p["cage"] @ Y, Xs), p["Wa"] @ Xs)
    del Xs        # (made again in each sweep: one array fewer alive there)
    fixed = _sum(p["rhs"] @ Y, fixed)
    for _ in range(sweeps):
        l = _sum(p["rows"] @ Y, p["Bu"] @ c)              # l_v = X_v + B c at the rows
        # new = blk (fixed + BsT (Dp T - Dpp l)), T = gather agg l the sum of the sample's P l
        u = _diff(p["Dp"] @ (p["gather"] @ (p["agg"] @ l)), p["Dpp"] @ l)
        del l
        new = p["blk"] @ _sum(fixed, p["BsT"] @ u)
        del u
        c = _project(proj, (1.0 - d) * c + d * new, Y)
        if sp.issparse(c):
            c.eliminate_zeros()
    return c


class SelectedFits:
    """A coefficient map ``inner`` of positions X' = X[source] (V', k) as a map of X (V, k):
    ``fits(X) = inner(X[source])`` (V' MMAX, k); :attr:`operator` (V' MMAX, V) sums the
    columns of the rows of X' that select the same vertex. Same interface as
    :class:`CoupledFits`. Serves the cut mesh of creases (``source`` = copy_of) and the
    repaired mesh (``source`` = vertex_map)."""

    def __init__(self, inner, source, n_source: int):
        self.inner = inner
        self.source = np.asarray(source, dtype=np.int64)
        self.shape = (inner.shape[0], int(n_source))

    def __call__(self, X):
        return self.inner(np.asarray(X, dtype=np.float64)[self.source])

    @cached_property
    def operator(self) -> sp.csr_matrix:
        op = (self.inner.operator @ selection_matrix(self.source, self.shape[1])).tocsr()
        op.sum_duplicates()
        op.eliminate_zeros()
        return op

    @property
    def operator_built(self) -> bool:
        return "operator" in self.__dict__

    def columns(self, cols) -> sp.csc_matrix:
        """Columns ``cols`` (vertices of X) of :attr:`operator` (csc), from the inner map's
        columns of the rows selecting them (each added to its vertex's)."""
        cols = np.asarray(cols, dtype=np.int64).ravel()
        if self.operator_built:
            return self.operator.tocsc()[:, cols]
        mine = np.flatnonzero(np.isin(self.source, cols))
        at = np.searchsorted(np.sort(cols), self.source[mine])
        sel = sp.csr_matrix((np.ones(len(mine)), (np.arange(len(mine)), np.argsort(cols)[at])),
                            shape=(len(mine), len(cols)))
        return (self.inner.columns(mine) @ sel).tocsc()


def identity_fits(chosen, projection=None) -> CoupledFits:
    """The chosen data fits alone (no coupling sweeps), constrained by ``projection``
    ((R, K, G), :meth:`gerbs_core.mesh.crease_fits.CurveConstraints.projection`) if given."""
    return CoupledFits(chosen, projection=projection)


def _block_diagonal(blocks):
    """csr of the block-diagonal matrix with (V, M, M) blocks (zero entries dropped)."""
    V, M, _ = blocks.shape
    r = (np.arange(V)[:, None, None] * M + np.arange(M)[None, :, None]).repeat(M, 2)
    c = (np.arange(V)[:, None, None] * M + np.arange(M)[None, None, :]).repeat(M, 1)
    nz = blocks != 0
    return sp.csr_matrix((blocks[nz], (r[nz], c[nz])), shape=(V * M, V * M))


def _diagonal(values, one):
    """sp.diags(values, format="csr") (its zeros dropped), the index arrays views of
    ``one`` = arange(n + 1) when no value is zero."""
    if not np.all(values != 0):
        return sp.diags(values, format="csr")
    n = len(values)
    return sp.csr_matrix((values, one[:n], one), shape=(n, n))


def _same_pattern(m, like):
    """csr m with the index arrays of ``like`` when both have one pattern (no second copy)."""
    if (m.shape == like.shape and np.array_equal(m.indptr, like.indptr)
            and np.array_equal(m.indices, like.indices)):
        return sp.csr_matrix((m.data, like.indices, like.indptr), shape=m.shape)
    return m


def coupled_fits(chosen, rhs, normals, degrees, smp, rule, h, dmax,
                 constraints=None, mu=None) -> CoupledFits:
    """The coupled fits (module docstring), with optional linear ``constraints``
    (:class:`gerbs_core.mesh.crease_fits.CurveConstraints`) imposed after the first fit and
    every sweep in the metric of the coupled normal matrices.

    chosen, rhs (V MMAX, V): the chosen candidates' coefficient operators and the
    right-hand sides of their scaled normal equations; normals (V, MMAX, MMAX) their
    normal matrices (scaled coordinates, zero-padded); degrees (V,); smp the energies'
    samples (:class:`gerbs_core.mesh.agreement._Samples`); rule the FairnessRule; h (V,)
    the fit scales; dmax the padded layout's degree (MMAX = n_monomials(dmax)); mu the
    agreement weight, a scalar or (SC,) per row (default ``rule.mu``;
    :func:`gerbs_core.mesh.agreement.row_mu`).
    """
    V = len(degrees)
    mmax = n_monomials(dmax)
    deg = monomial_exponents(dmax).sum(1)
    SC, L = len(smp.vertex), smp.n_samples
    P, w, s = smp.psi, smp.weight, smp.sharp
    mu = rule.mu if mu is None else mu
    wa = mu * w * P * (1.0 - P)                       # agreement weight of each row
    wt = rule.lam * w * s * P                         # tension weight
    # the rows' monomials, only those of each vertex's own degree (the others have zero
    # coefficients): Bu (SC, V MMAX) csr and the scaled Bs^T (V MMAX, SC) csc, built
    # directly in compressed form (no coo sort: these are the largest matrices)
    per_row = n_monomials(np.asarray(degrees))[smp.vertex]       # active monomials of a row
    active = np.arange(mmax)[None, :] < per_row[:, None]
    # (one pattern: int32 index arrays shared by both matrices, not a copy each)
    idx = np.int32 if max(V * mmax, active.size, L) < 2 ** 31 - 1 else np.int64
    cols = (smp.vertex[:, None] * mmax + np.arange(mmax))[active].astype(idx)
    ptr = np.zeros(SC + 1, dtype=idx)
    np.cumsum(per_row, out=ptr[1:])
    del per_row
    bu = smp.Bu[active]
    Bu = sp.csr_matrix((bu, cols, ptr), shape=(SC, V * mmax))
    # Bs = Bu / h_v^|m| entry by entry (the values of smp.Bs, without its dense array)
    BsT = sp.csc_matrix((bu / smp.hpow.ravel()[cols], cols, ptr), shape=(V * mmax, SC))
    del bu, active
    # per vertex normal matrices of data + agreement + tension (block diagonal B^T W B)
    N = normals.copy()
    # (the rows' weights scale BsT's columns in place of a product with a diagonal matrix)
    BsTw = sp.csc_matrix((BsT.data * np.repeat(wa + wt, np.diff(BsT.indptr)), BsT.indices,
                          BsT.indptr), shape=BsT.shape)
    G2 = (BsTw @ BsT.T).tocoo()
    del BsTw
    N[G2.row // mmax, G2.row % mmax, G2.col % mmax] += G2.data
    Pinv = np.zeros_like(N)
    for d in np.unique(degrees).tolist():
        vs = np.flatnonzero(degrees == d)
        M = n_monomials(d)
        Pinv[vs, :M, :M] = pinned_normal_inverse(N[vs, :M, :M], d, certified=True)
    Pinv = Pinv / h[:, None, None] ** deg[None, :, None]      # unscale: c = scaled / h^|m|
    # the one-entry-per-row matrices share their arrays (the pointers 0..SC, the column
    # indices of the diagonals, the ones): the model keeps them for partial updates
    one, ones = np.arange(SC + 1, dtype=idx), np.ones(SC)
    gather = sp.csr_matrix((ones, smp.sample.astype(idx), one), shape=(SC, L))
    parts = {
        "blk": _block_diagonal(Pinv),
        "rhs": _same_pattern(rhs.tocsr(), chosen.tocsr()),
        "BsT": BsT,
        "rows": sp.csr_matrix((ones, smp.vertex.astype(idx), one), shape=(SC, V)),
        "cage": (gather @ smp.cage).tocsr(),
        "Bu": Bu,
        "gather": gather,
        "agg": sp.csc_matrix((P, gather.indices, one), shape=(L, SC)),
        "Wt": _diagonal(wt, one),
        "Wa": _diagonal(wa, one),
        "Dp": _diagonal(mu * w * P, one),
        "Dpp": _diagonal(mu * w * P * P, one),
    }
    proj = None if constraints is None else constraints.projection(N, h, degrees, mmax)
    return CoupledFits(chosen, rule.sweeps, rule.damping, parts, proj)
