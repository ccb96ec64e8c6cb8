"""Assembly of the stencil factors B (P, V) and E (P, V M) on a sample lattice.

For every sample p, evaluated in the face that owns it, and every corner slot k
of that face: B[p, u_k] = Psi_k(p), E[p, u_k M + m] = Psi_k(p) mono_m(zeta_{u_k}(p))
(:mod:`gerbs_core.mesh.stencil`). Vectorized per face-size class and chunk
(:func:`gerbs_core.mesh.evaluate.groups`).

Both factors are written straight into their compressed-row arrays: the entries of
a row are known in advance (B: one per corner of the sample's face; E: the
coefficients of each corner's degree, lower degrees skipping the monomials they do
not have), so each chunk scatters its values to their final places and no
coordinate-format copy (three times the memory) is ever made. Values float64,
indices int32 while they fit.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .agreement import MMAX
from .evaluate import corner_terms, groups

__all__ = ["assemble", "n_monomials"]


def n_monomials(d):
    """Coefficients of a local function of degree d (monomials of degree 1..d in 2D)."""
    return d * (d + 3) // 2


def _row_layout(topo, degrees, face):
    """Per sample (face (P,)): the row pointers of B and E (int64, (P + 1,))."""
    sizes = topo.face_sizes
    per_face_e = np.add.reduceat(n_monomials(degrees[topo.face_vertices]),
                                 topo.face_offsets[:-1])
    ptr_b = np.zeros(len(face) + 1, dtype=np.int64)
    ptr_e = np.zeros(len(face) + 1, dtype=np.int64)
    np.cumsum(sizes[face], out=ptr_b[1:])
    np.cumsum(per_face_e[face], out=ptr_e[1:])
    return ptr_b, ptr_e


def _index_type(nnz, n_cols):
    return np.int32 if max(nnz, n_cols) < 2 ** 31 - 1 else np.int64


def assemble(model, lattice):
    """(B csr (P, V), E csr (P, V MMAX), eps) on ``lattice``; eps = min max_v psi_v.

    Rows are in sample order with sorted column indices (canonical csr)."""
    topo, deg = model.topology, np.asarray(model.degrees)
    x = lattice.map_to_polygon(model.layouts.corners)
    P, V = lattice.n_points, topo.n_vertices
    ptr_b, ptr_e = _row_layout(topo, deg, lattice.face)
    ib, ie = _index_type(ptr_b[-1], V), _index_type(ptr_e[-1], V * MMAX)
    data_b, cols_b = np.empty(ptr_b[-1]), np.empty(ptr_b[-1], dtype=ib)
    data_e, cols_e = np.empty(ptr_e[-1]), np.empty(ptr_e[-1], dtype=ie)
    eps = np.inf
    for n, faces, sel, xb in groups(topo, model.layouts.corners, lattice.face, x):
        u = topo.face_vertices[topo.face_offsets[faces][None, :] + np.arange(n)[:, None]]
        _, Psi, mono, mx = corner_terms(model, n, faces, xb, 0, int(deg[u].max()))
        valid = sel >= 0
        eps = min(eps, float(mx[valid].min()))
        rows = sel[valid]                                                    # (S,)
        uu = np.broadcast_to(u[:, :, None], Psi[0].shape)[:, valid]          # (n, S)
        w = Psi[0][:, valid]
        at = ptr_b[rows][None, :] + np.arange(n)[:, None]
        data_b[at], cols_b[at] = w, uu
        # E: slot k's entries start after the coefficients of slots < k in the row
        Mk = n_monomials(deg[uu])                                            # (n, S)
        start = ptr_e[rows][None, :] + np.cumsum(Mk, axis=0) - Mk
        M = mono[0].shape[-1]
        keep = np.arange(M)[None, None, :] < Mk[..., None]
        at = (start[..., None] + np.arange(M))[keep]
        data_e[at] = (mono[0][:, valid] * w[..., None])[keep]
        cols_e[at] = (uu[..., None] * MMAX + np.arange(M))[keep]
    B = sp.csr_matrix((data_b, cols_b, ptr_b.astype(ib)), shape=(P, V))
    E = sp.csr_matrix((data_e, cols_e, ptr_e.astype(ie)), shape=(P, V * MMAX))
    B.sort_indices()
    E.sort_indices()
    return B, E, eps
