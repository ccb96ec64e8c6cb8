"""Assembly of the stencil factors B (P, V) and E (P, V M) on a sample lattice.

For every sample p, evaluated in the face that owns it, and every corner slot k
of that face: B[p, u_k] = Psi_k(p), E[p, u_k M + m] = Psi_k(p) mono_m(zeta_{u_k}(p))
(:mod:`gerbs_core.mesh.stencil`). Vectorized per face-size class and chunk
(:func:`gerbs_core.mesh.evaluate.groups`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .agreement import MMAX
from .evaluate import corner_terms, groups

__all__ = ["assemble"]


def assemble(model, lattice):
    """(B csr (P, V), E csr (P, V MMAX), eps) on ``lattice``; eps = min max_v psi_v."""
    topo = model.topology
    x = lattice.map_to_polygon(model.layouts.corners)
    P, V = lattice.n_points, topo.n_vertices
    rb, cb, vb, re, ce, ve = [], [], [], [], [], []
    eps = np.inf
    for n, faces, sel, xb in groups(topo, model.layouts.corners, lattice.face, x):
        u = topo.face_vertices[topo.face_offsets[faces][None, :] + np.arange(n)[:, None]]
        d = int(model.degrees[u].max())
        _, Psi, mono, mx = corner_terms(model, n, faces, xb, 0, d)
        valid = sel >= 0
        eps = min(eps, float(mx[valid].min()))
        rows = np.broadcast_to(sel[None], Psi[0].shape)[:, valid]          # (n, S)
        uu = np.broadcast_to(u[:, :, None], Psi[0].shape)[:, valid]
        w = Psi[0][:, valid]
        rb.append(rows.ravel()), cb.append(uu.ravel()), vb.append(w.ravel())
        M = mono[0].shape[-1]
        m = mono[0][:, valid] * w[..., None]                                 # (n, S, M)
        # local functions of lower degree have zero coefficients beyond their M: skip them
        keep = np.arange(M)[None, None, :] < _n_mono(model.degrees[uu])[..., None]
        re.append(np.broadcast_to(rows[..., None], m.shape)[keep])
        ce.append((uu[..., None] * MMAX + np.arange(M))[keep])
        ve.append(m[keep])
    B = sp.csr_matrix((np.concatenate(vb), (np.concatenate(rb), np.concatenate(cb))), shape=(P, V))
    E = sp.csr_matrix((np.concatenate(ve), (np.concatenate(re), np.concatenate(ce))),
                      shape=(P, V * MMAX))
    return B, E, eps


def _n_mono(d):
    return d * (d + 3) // 2
