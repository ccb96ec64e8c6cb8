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

Faces equal in every bit of their rows' inputs (:mod:`.face_classes`: a regular grid's
faces) have equal rows at equal template points: where the classes' template points are
at most ``SHARED_FRACTION`` of the samples, each class is evaluated once, at the points
of its representative face, and the rows are copied to the samples (bit for bit the
values of evaluating every sample; the columns come from each face's own vertices).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .agreement import MMAX
from .arrays import ranges
from .face_classes import face_classes
from .lattice_templates import INTERIOR, template
from .monomials import monomial_exponents, n_monomials, powers
from .polygon_map import map_points

__all__ = ["assemble", "CHUNK_SAMPLES", "SHARED_FRACTION"]

CHUNK_SAMPLES = 16_384   # samples per chunk at most (~65k terms on quads: the working set in cache)
# evaluate face classes once when their template points are at most this share of the
# samples (every template point of a representative is evaluated, shared ones included)
SHARED_FRACTION = 0.5
LONG_RUN = 16            # rows copied as one slice (shorter runs: one gather for all)


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
    per degree one scatter of its terms' (n, M) blocks to their runs of slots.
    ``cols_e`` None: values only."""
    T = len(w)
    sizes = np.flatnonzero(np.bincount(Mt)).tolist()     # the terms' coefficient counts
    ptr = None
    y0, y1 = np.ascontiguousarray(y[:, 0]), np.ascontiguousarray(y[:, 1])
    for M in sizes:
        d = _degree_of(M)
        E = monomial_exponents(d)
        one = len(sizes) == 1
        sel = None if one else np.flatnonzero(Mt == M)
        ww = w if one else w[sel]
        cv = (vertex if one else vertex[sel]) * MMAX
        p1 = powers(y0 if one else y0[sel], d)
        p2 = powers(y1 if one else y1[sel], d)
        if one:
            dv = data_e[e0:e0 + T * M].reshape(T, M)
            dc = None if cols_e is None else cols_e[e0:e0 + T * M].reshape(T, M)
        else:
            dv = np.empty((len(sel), M))
            dc = None if cols_e is None else np.empty((len(sel), M), dtype=cols_e.dtype)
        val = np.empty(len(ww))
        for m, (a, b) in enumerate(E):
            np.multiply(p1[a], p2[b], out=val)
            np.multiply(val, ww, out=dv[:, m])
            if dc is not None:
                np.add(cv, m, out=dc[:, m])
        if not one:
            if ptr is None:
                ptr = np.zeros(T + 1, dtype=np.int64)
                np.cumsum(Mt, out=ptr[1:])
            slots = (e0 + ptr[sel])[:, None] + np.arange(M)
            data_e[slots] = dv
            if dc is not None:
                cols_e[slots] = dc


def _degree_of(M):
    return {n_monomials(d): d for d in range(1, 8)}[M]


def _evaluate_rows(model, face, x_of, ptr_b, ptr_e, by_vertex, out_b, out_e, chunk):
    """Write the rows of the samples (face (N,), x_of(p0, p1) -> (p1 - p0, 2) the points of
    samples p0..p1 in their faces: made chunk by chunk) into
    ``out_b`` = (data, cols or None) and ``out_e`` likewise at the row pointers ptr_b,
    ptr_e (N + 1,), ``chunk`` samples at a time; returns max_k psi_k per sample (N,)."""
    topo, ch, cover = model.topology, model.charts, model.cover
    Mv = n_monomials(np.asarray(model.degrees))
    n_max = int(topo.face_sizes.max())
    N = len(face)
    mx = np.empty(N)
    for p0 in range(0, N, chunk):
        p1 = min(N, p0 + chunk)
        terms = _Terms(topo, by_vertex, face, ptr_b, p0, p1)
        xt = x_of(p0, p1)[terms.sample]
        psi, pol = cover.psi_jet(ch, terms.corner, xt, 0)
        w, mx[p0:p1] = _partition(psi[0], terms, p1 - p0, n_max)
        t0, t1 = ptr_b[p0], ptr_b[p1]
        out_b[0][t0:t1] = w
        if out_b[1] is not None:
            out_b[1][t0:t1] = terms.vertex
        y = ch.to_chart(terms.corner, xt, 0, pol=pol)[0]
        _write_mono(out_e[0], out_e[1], ptr_e[p0], y, w, terms.vertex, Mv[terms.vertex])
    return mx


def _gather_rows(src, src_ptr, rows, dst_ptr, step):
    """The rows ``rows`` (N,) of the ragged array (src, src_ptr) one after another (their
    lengths np.diff(dst_ptr)). Runs of rows that step by ``step`` (1: the next row, 0:
    the same row) are copied as slices, the short ones gathered together."""
    out = np.empty(dst_ptr[-1], dtype=src.dtype)
    cut = np.flatnonzero(np.diff(rows) != step) + 1
    first = np.concatenate([[0], cut])
    length = np.diff(np.concatenate([first, [len(rows)]]))
    long = length >= LONG_RUN
    a, n = first[long], length[long]
    r0 = rows[a]
    # every long run's slice bounds at once: the loop only copies (one slice per run)
    bounds = zip(dst_ptr[a].tolist(), dst_ptr[a + n].tolist(), src_ptr[r0].tolist(),
                 src_ptr[r0 + (n if step else 1)].tolist(), n.tolist())
    for d0, d1, s0, s1, k in bounds:
        if step:
            out[d0:d1] = src[s0:s1]
        else:
            out[d0:d1].reshape(k, s1 - s0)[:] = src[s0:s1]
    short = np.repeat(~long, length)
    s = np.flatnonzero(short)
    lens = dst_ptr[s + 1] - dst_ptr[s]
    out[ranges(dst_ptr[s], lens)] = src[ranges(src_ptr[rows[s]], lens)]
    return out


def _shared(model, lattice, classes, by_vertex, ptr_b, ptr_e, ib, ie, chunk):
    """(data_b, cols_b, data_e, cols_e, eps) with every face class
    (:mod:`.face_classes`) evaluated once, at the template points of its representative
    face, and the rows copied to the samples of all its faces."""
    topo, deg = model.topology, np.asarray(model.degrees)
    r = lattice.resolution
    face, uv, fan, src = [], [], [], np.empty(lattice.n_points, dtype=np.int64)
    off = 0
    for (fk, G, own, n), cls, rep in zip(lattice.size_classes, classes.cls, classes.rep):
        tuv, tfan, kind, loc = template(n, r)[:4]
        # the interior points first, in their samples' order: a face's interior samples
        # are then one run of rows of its class (copied as one slice)
        order = np.lexsort((loc, kind != INTERIOR))
        at = np.empty(len(order), dtype=np.int64)
        at[order] = np.arange(len(order))
        npt = len(tfan)
        face.append(np.repeat(rep, npt))
        uv.append(np.tile(tuv[order], (len(rep), 1)))
        fan.append(np.tile(tfan[order], len(rep)))
        ii, jj = np.nonzero(own)
        src[G[ii, jj]] = off + cls[ii] * npt + at[jj]
        off += len(rep) * npt
    face, uv, fan = np.concatenate(face), np.concatenate(uv), np.concatenate(fan)
    x = map_points(topo, np.asarray(model.layouts.corners, dtype=np.float64), face, fan, uv)
    qb, qe = _row_layout(topo, deg, face)
    tab_b, tab_e = np.empty(qb[-1]), np.empty(qe[-1])
    mx = _evaluate_rows(model, face, lambda p0, p1: x[p0:p1], qb, qe, by_vertex,
                        (tab_b, None), (tab_e, None), chunk)
    sface = lattice.face
    sorted_vertex = topo.face_vertices[by_vertex].astype(ib)
    Mc = n_monomials(deg[topo.face_vertices[by_vertex]])
    pattern = ranges(topo.face_vertices[by_vertex] * MMAX, Mc).astype(ie)
    pptr = np.zeros(topo.n_faces + 1, dtype=np.int64)
    np.cumsum(np.add.reduceat(Mc, topo.face_offsets[:-1]), out=pptr[1:])
    return (_gather_rows(tab_b, qb, src, ptr_b, 1),
            _gather_rows(sorted_vertex, topo.face_offsets, sface, ptr_b, 0),
            _gather_rows(tab_e, qe, src, ptr_e, 1),
            _gather_rows(pattern, pptr, sface, ptr_e, 0), float(mx[src].min()))


def assemble(model, lattice, chunk: int = CHUNK_SAMPLES):
    """(B csr (P, V), E csr (P, V MMAX), eps) on ``lattice``; eps = min max_v psi_v.
    ``chunk``: samples evaluated per step (every row is computed alone: the factors are
    bit for bit the same for every chunk).

    Rows are in sample order with sorted column indices (canonical csr). Faces of one
    class (:mod:`.face_classes`) are evaluated once where the classes hold at most
    ``SHARED_FRACTION`` of the samples' work."""
    topo, deg = model.topology, np.asarray(model.degrees)
    face = lattice.face
    P, V = lattice.n_points, topo.n_vertices
    ptr_b, ptr_e = _row_layout(topo, deg, face)
    ib, ie = _index_type(ptr_b[-1], V), _index_type(ptr_e[-1], V * MMAX)
    by_vertex = _sorted_corners(topo)
    classes = face_classes(model, lattice, by_vertex)
    work = sum(len(rep) * G.shape[1] for rep, (_, G, _, _) in zip(classes.rep,
                                                                  lattice.size_classes))
    if work <= SHARED_FRACTION * P:
        data_b, cols_b, data_e, cols_e, eps = _shared(model, lattice, classes, by_vertex,
                                                      ptr_b, ptr_e, ib, ie, chunk)
    else:
        # the samples' points chunk by chunk (the same formulas per sample as
        # lattice.map_to_polygon), from parameters not cached on the lattice: neither
        # (P, 2) array outlives the assembly (a stencil keeps its lattice)
        uv, fan = lattice.sample_params()
        corners = np.asarray(model.layouts.corners, dtype=np.float64)

        def x_of(p0, p1):
            return map_points(topo, corners, face[p0:p1], fan[p0:p1], uv[p0:p1])

        data_b, cols_b = np.empty(ptr_b[-1]), np.empty(ptr_b[-1], dtype=ib)
        data_e, cols_e = np.empty(ptr_e[-1]), np.empty(ptr_e[-1], dtype=ie)
        mx = _evaluate_rows(model, face, x_of, ptr_b, ptr_e, by_vertex, (data_b, cols_b),
                            (data_e, cols_e), chunk)
        eps = float(mx.min()) if P else np.inf
    B = sp.csr_matrix((data_b, cols_b, ptr_b.astype(ib)), shape=(P, V))
    E = sp.csr_matrix((data_e, cols_e, ptr_e.astype(ie)), shape=(P, V * MMAX))
    B.has_canonical_format = E.has_canonical_format = True
    return B, E, eps
