"""Assembly of the stencil factors B (P, V) and E (P, V M) on a sample lattice.

For every sample p, evaluated in the face that owns it, and every corner k of that
face: B[p, u_k] = Psi_k(p), E[p, u_k M + m] = Psi_k(p) mono_m(zeta_{u_k}(p))
(:mod:`gerbs_core.mesh.stencil`).

The work is organised by *terms* (sample, corner), listed in the final order of the
compressed rows: samples in order, and within a sample its face's corners by
increasing vertex (so the column indices of both factors come out sorted). Then B's
values are the partition values Psi of the terms as they come, and E's values are
every term's Psi mono_m for its degree's monomials, one term after another: both
factors are written in contiguous slices of their final arrays, chunk by chunk of
samples, with no scatter, no coordinate-format copy and no index sort. Values
float64, indices int32 while they fit.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .agreement import MMAX
from .monomials import monomial_exponents, n_monomials, powers

__all__ = ["assemble", "CHUNK_SAMPLES"]

CHUNK_SAMPLES = 16_384   # samples per chunk (~65k terms on quads: the working set in cache)


def _row_layout(topo, degrees, face):
    """Per sample (face (P,)): the row pointers of B and E (int64, (P + 1,))."""
    per_face_e = np.add.reduceat(n_monomials(degrees[topo.face_vertices]),
                                 topo.face_offsets[:-1])
    ptr_b = np.zeros(len(face) + 1, dtype=np.int64)
    ptr_e = np.zeros(len(face) + 1, dtype=np.int64)
    np.cumsum(topo.face_sizes[face], out=ptr_b[1:])
    np.cumsum(per_face_e[face], out=ptr_e[1:])
    return ptr_b, ptr_e


def _index_type(nnz, n_cols):
    return np.int32 if max(nnz, n_cols) < 2 ** 31 - 1 else np.int64


def _sorted_corners(topo):
    """(C,): entry fo[f] + j is the corner of face f with the j-th smallest vertex."""
    return np.lexsort((topo.face_vertices, topo.corner_face))


class _Terms:
    """The terms (sample, corner) of the samples [p0, p1) in row order: ``sample`` (T,)
    local sample index, ``corner`` (T,), ``slot`` (T,) the corner's position in its
    face, ``vertex`` (T,)."""

    def __init__(self, topo, by_vertex, face, ptr_b, p0, p1):
        t0, t1 = ptr_b[p0], ptr_b[p1]
        counts = np.diff(ptr_b[p0:p1 + 1])
        self.sample = np.repeat(np.arange(p1 - p0), counts)
        first = topo.face_offsets[face[p0:p1]]
        rank = np.arange(t1 - t0) - (ptr_b[p0:p1] - t0)[self.sample]
        at = first[self.sample] + rank
        self.corner = by_vertex[at]
        self.slot = self.corner - first[self.sample]
        self.vertex = topo.face_vertices[self.corner]


def _partition(psi, terms, n_samples, n_max):
    """Psi (T,) = psi / sum over the sample's corners, summed in corner order (as the
    evaluation does), and max_k psi_k per sample (n_samples,)."""
    per = np.zeros((n_max, n_samples))
    per[terms.slot, terms.sample] = psi
    total = per[0].copy()
    for k in range(1, n_max):
        total += per[k]
    with np.errstate(invalid="ignore", divide="ignore"):
        return psi / total[terms.sample], per.max(axis=0)


def _write_mono(data_e, cols_e, e0, y, w, vertex, Mt):
    """E's entries of the terms (their values Psi mono_m and columns u M + m), term after
    term from e0: strided views of the output when all terms share one degree, else
    one scatter per degree and monomial."""
    T = len(w)
    ptr = np.zeros(T + 1, dtype=np.int64)
    np.cumsum(Mt, out=ptr[1:])
    y0, y1 = np.ascontiguousarray(y[:, 0]), np.ascontiguousarray(y[:, 1])
    for M in np.unique(Mt).tolist():
        d = _degree_of(M)
        E = monomial_exponents(d)
        sel = None if ptr[-1] == T * M and Mt.min() == M else np.flatnonzero(Mt == M)
        ww = w if sel is None else w[sel]
        cv = (vertex if sel is None else vertex[sel]) * MMAX
        p1 = powers(y0 if sel is None else y0[sel], d)
        p2 = powers(y1 if sel is None else y1[sel], d)
        val = np.empty(len(ww))
        if sel is None:
            dv = data_e[e0:e0 + T * M].reshape(T, M)
            dc = cols_e[e0:e0 + T * M].reshape(T, M)
        else:
            start = e0 + ptr[sel]
        for m, (a, b) in enumerate(E):
            np.multiply(p1[a], p2[b], out=val)
            if sel is None:
                np.multiply(val, ww, out=dv[:, m])
                np.add(cv, m, out=dc[:, m])
            else:
                data_e[start + m] = val * ww
                cols_e[start + m] = cv + m


def _degree_of(M):
    return {n_monomials(d): d for d in range(1, 8)}[M]


def assemble(model, lattice):
    """(B csr (P, V), E csr (P, V MMAX), eps) on ``lattice``; eps = min max_v psi_v.

    Rows are in sample order with sorted column indices (canonical csr)."""
    topo, deg = model.topology, np.asarray(model.degrees)
    ch, cover = model.charts, model.cover
    x = lattice.map_to_polygon(model.layouts.corners)
    face = lattice.face
    P, V = lattice.n_points, topo.n_vertices
    ptr_b, ptr_e = _row_layout(topo, deg, face)
    ib, ie = _index_type(ptr_b[-1], V), _index_type(ptr_e[-1], V * MMAX)
    data_b, cols_b = np.empty(ptr_b[-1]), np.empty(ptr_b[-1], dtype=ib)
    data_e, cols_e = np.empty(ptr_e[-1]), np.empty(ptr_e[-1], dtype=ie)
    by_vertex = _sorted_corners(topo)
    Mv = n_monomials(deg)
    n_max = int(topo.face_sizes.max())
    eps = np.inf
    for p0 in range(0, P, CHUNK_SAMPLES):
        p1 = min(P, p0 + CHUNK_SAMPLES)
        terms = _Terms(topo, by_vertex, face, ptr_b, p0, p1)
        xt = x[p0:p1][terms.sample]
        psi, pol = cover.psi_jet(ch, terms.corner, xt, 0)
        w, mx = _partition(psi[0], terms, p1 - p0, n_max)
        eps = min(eps, float(mx.min()))
        t0, t1 = ptr_b[p0], ptr_b[p1]
        data_b[t0:t1] = w
        cols_b[t0:t1] = terms.vertex
        y = ch.to_chart(terms.corner, xt, 0, pol=pol)[0]
        _write_mono(data_e, cols_e, ptr_e[p0], y, w, terms.vertex, Mv[terms.vertex])
    B = sp.csr_matrix((data_b, cols_b, ptr_b.astype(ib)), shape=(P, V))
    E = sp.csr_matrix((data_e, cols_e, ptr_e.astype(ie)), shape=(P, V * MMAX))
    B.has_canonical_format = E.has_canonical_format = True
    return B, E, eps
