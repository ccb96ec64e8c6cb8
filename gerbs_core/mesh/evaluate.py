"""Evaluation of S(p) = sum_v Psi_v(p) l_v(zeta_v(p)) and its derivatives (pure functions).

Samples are grouped by the size n of their face and padded per face; every
quantity is computed per corner slot k for all faces of a size class at once
(arrays (n, F, P, ...)), in chunks of bounded size. Only the corners of the
face containing p contribute: every other size function vanishes there (supp
psi_v lies inside v's open star). Derivatives are with respect to the face's
layout coordinates; all closed form (the kernel's F to its table accuracy).
"""
from __future__ import annotations

import numpy as np

from ..gauge.jet import partition_jet
from .monomials import monomials

__all__ = ["groups", "corner_terms", "evaluate", "partition_at", "CHUNK"]

CHUNK = 200_000  # sample x corner terms per chunk at most (default budgets)


def groups(topo, corners2d, face_ids, x, chunk: int = CHUNK):
    """Group samples (face_ids (N,), x (N, 2)) by face size, padded per face.

    Yields (n, faces (F,), sel (F, P) sample index or -1, xb (F, P, 2)) with at most
    ``chunk`` padded sample x corner terms F P n per item (at least one face); padding
    points sit at the face's centroid (inside, harmless) and have sel = -1. Every
    face's points are computed alone (no sum runs across faces), so the chunking does
    not change the bits of any result.
    """
    order = np.argsort(face_ids, kind="stable")
    fs = face_ids[order]
    uf, start, counts = np.unique(fs, return_index=True, return_counts=True)
    sizes = topo.face_sizes[uf]
    cen = np.add.reduceat(corners2d, topo.face_offsets[:-1], axis=0) / topo.face_sizes[:, None]
    for n in np.unique(sizes).tolist():
        kk = np.flatnonzero(sizes == n)
        P = int(counts[kk].max())
        faces = uf[kk]
        rank = np.arange(P)[None, :]
        valid = rank < counts[kk][:, None]
        sel = np.where(valid, order[np.minimum(start[kk][:, None] + rank, len(order) - 1)], -1)
        xb = np.where(valid[..., None], x[np.maximum(sel, 0)], cen[faces][:, None, :])
        per = max(1, chunk // (P * n))
        for a in range(0, len(faces), per):
            yield n, faces[a:a + per], sel[a:a + per], xb[a:a + per]


def corner_terms(model, n, faces, xb, nu: int, degree: int | None = None):
    """Per corner slot k of n-gon faces (F,) at points xb (F, P, 2):

    (u (n, F) corner vertices, Psi jet (n, F, P, ...), monomial jet (n, F, P, M, ...)
    chained to face coordinates, max_k psi_k (F, P)). degree: monomials up to it
    (default: the model's highest local degree).
    """
    topo, ch = model.topology, model.charts
    corners = topo.face_offsets[faces][None, :] + np.arange(n)[:, None]   # (n, F)
    cb = np.broadcast_to(corners[:, :, None], (n,) + xb.shape[:2])
    psi, pol = model.cover.psi_jet(ch, cb, xb[None], nu)
    Psi = partition_jet(psi, nu)
    u = topo.face_vertices[corners]
    d = model.max_degree if degree is None else degree
    yy = ch.to_chart(cb, xb[None], nu, pol=pol)
    mm = monomials(yy[0], d, nu)
    mono = [mm[0]]
    if nu >= 1:
        mono.append(np.einsum("...mi,...ij->...mj", mm[1], yy[1]))
    if nu >= 2:
        J = yy[1]
        mono.append(np.einsum("...mik,...ij,...kl->...mjl", mm[2], J, J)
                    + np.einsum("...mi,...ijk->...mjk", mm[1], yy[2]))
    return u, Psi, mono, psi[0].max(axis=0)


def _blend(Psi, mono, Xu, Cu, nu):
    """[S, dS, d2S] per face point from the corner terms (slots summed)."""
    lval = Xu[:, :, None, :] + np.einsum("kfpm,kfmc->kfpc", mono[0], Cu)
    res = [np.einsum("kfp,kfpc->fpc", Psi[0], lval)]
    if nu >= 1:
        dl = np.einsum("kfpmj,kfmc->kfpcj", mono[1], Cu)
        res.append(np.einsum("kfpj,kfpc->fpcj", Psi[1], lval)
                   + np.einsum("kfp,kfpcj->fpcj", Psi[0], dl))
    if nu >= 2:
        Hl = np.einsum("kfpmjl,kfmc->kfpcjl", mono[2], Cu)
        res.append(np.einsum("kfpjl,kfpc->fpcjl", Psi[2], lval)
                   + np.einsum("kfpj,kfpcl->fpcjl", Psi[1], dl)
                   + np.einsum("kfpcj,kfpl->fpcjl", dl, Psi[1])
                   + np.einsum("kfp,kfpcjl->fpcjl", Psi[0], Hl))
    return res


def evaluate(model, X, coef, face_ids, x, nu: int, chunk: int = CHUNK):
    """S and its derivatives up to nu at face points (face_ids (N,), x (N, 2)).

    X (V, k) positions, coef (V, M, k) local-function coefficients; ``chunk``: padded
    sample x corner terms per step (:func:`groups`; the result is bit for bit the same
    for every chunk). Returns
    ([S (N, k), dS (N, k, 2), d2S (N, k, 2, 2)][:nu + 1], eps) with eps the smallest
    max_v psi_v over the points (> 0: every point is covered).
    """
    N, k = len(face_ids), X.shape[1]
    out = [np.zeros((N, k)), np.zeros((N, k, 2)), np.zeros((N, k, 2, 2))][:nu + 1]
    eps = np.inf
    M = coef.shape[1]
    for n, faces, sel, xb in groups(model.topology, model.layouts.corners, face_ids, x, chunk):
        u = model.topology.face_vertices[model.topology.face_offsets[faces][None, :]
                                         + np.arange(n)[:, None]]
        d = int(model.degrees[u].max())
        _, Psi, mono, mx = corner_terms(model, n, faces, xb, nu, d)
        Mg = mono[0].shape[-1]
        valid = sel >= 0
        eps = min(eps, float(mx[valid].min()))
        res = _blend(Psi, mono, X[u], coef[u][:, :, :Mg] if Mg <= M else coef[u], nu)
        for o, r in zip(out, res):
            o[sel[valid]] = r[valid]
    return out, eps


def partition_at(model, f, x, nu):
    """The partition of unity (eq. (73)) at points x (N, 2) of faces f (N,):
    :meth:`gerbs_core.mesh.surface.BlendingSurface.partition` (vertices of the repaired
    mesh: with creases the copies' vertices)."""
    topo = model.topology
    nmax = int(topo.face_sizes.max())
    verts = np.full((len(f), nmax), -1, dtype=np.int64)
    Ps, ps, dP = np.zeros((len(f), nmax)), np.zeros((len(f), nmax)), np.zeros((len(f), nmax, 2))
    for n, faces, sel, xb in groups(topo, model.layouts.corners, f, x):
        u, Psi, _, _ = corner_terms(model, n, faces, xb, nu, degree=1)
        if model.crease is not None:
            u = model.crease.copy_of[u]
        cb = topo.face_offsets[faces][None, :, None] + np.arange(n)[:, None, None]
        psi = model.cover.psi_jet(model.charts, cb, xb[None], 0)[0][0]
        valid = sel >= 0
        s = sel[valid]
        for k in range(n):
            verts[s, k] = np.broadcast_to(u[k][:, None], valid.shape)[valid]
            Ps[s, k], ps[s, k] = Psi[0][k][valid], psi[k][valid]
            if nu >= 1:
                dP[s, k] = Psi[1][k][valid]
    return (verts, Ps, ps, dP) if nu >= 1 else (verts, Ps, ps)
