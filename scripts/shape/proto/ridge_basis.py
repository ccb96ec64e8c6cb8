"""The ridge basis of the prototype :mod:`ridges` (scripts/shape/proto): fixed smooth
non-polynomial ridge functions of a vertex's chart coordinate, fixed by the rest shape,
and the pinned least-squares candidate fit in the basis [monomials up to ``poly``, ridge
functions] (the padded degree-4 layout's 14 slots; unused ridge slots are 0 everywhere).

    line: r(y) = sqrt(t^2 + delta^2) - delta,  t = n . y (signed distance across the line of
          the sharp star edge through v), delta a fraction of the edge's chart length;
    half: r(y) sigma(s), s = e . y along the edge, sigma(s) = (1 + s / sqrt(s^2 + delta^2)) / 2
          (the ridge on the edge's side of v only).

r(0) = 0 and grad r(0) = 0: l_v(0) = X_v and the tangent plane at v is the polynomial
part's. A slot k's unscaled basis value is h^(deg_k - 1) r(y), so that its scaled value
(unscaled / h^deg_k, the layout's convention) is r(y) / h, dimensionless.
"""
import numpy as np
import scipy.sparse as sp

import gerbs_core.mesh.spread_fits as spf
from gerbs_core.mesh.fits import RCOND, CandidateFits
from gerbs_core.mesh.monomials import bending_gram, monomial_exponents, monomials, n_monomials

MM = 14                         # slots of the padded layout (degree 4)
DEG = monomial_exponents(4).sum(1)


class Ridges:
    """Ridge functions of the vertices: per vertex v (V,) a row ``at[v]`` (-1: none) of
    n (R, K, 2) (unit normal of the line), e (R, K, 2) (unit direction of the edge), delta
    (R, K) (0: unused slot), first slot p0 (the polynomial part's coefficient count)."""

    def __init__(self, at, n, e, delta, p0, kind):
        self.at, self.n, self.e, self.delta, self.p0, self.kind = at, n, e, delta, p0, kind

    def jet(self, vertex, y, nu):
        """[r (..., K), dr/dy (..., K, 2), d2r/dy2 (..., K, 2, 2)] up to nu of the ridge
        functions at rows (vertex (...), chart points y (..., 2)), every row's vertex one
        with ridges; exact (f(t) sigma(s) by the product rule)."""
        a = self.at[vertex]
        n, e, d = self.n[a], self.e[a], self.delta[a]            # (..., K, 2), (..., K)
        live = d > 0
        dd = np.where(live, d, 1.0)
        t = np.einsum("...kc,...c->...k", n, y)
        q = np.sqrt(t * t + dd * dd)
        f = np.where(live, q - dd, 0.0)
        f1 = np.where(live, t / q, 0.0)
        f2 = np.where(live, dd * dd / q ** 3, 0.0)
        if self.kind == "half":
            s = np.einsum("...kc,...c->...k", e, y)
            p = np.sqrt(s * s + dd * dd)
            g, g1, g2 = 0.5 * (1 + s / p), 0.5 * dd * dd / p ** 3, -1.5 * s * dd * dd / p ** 5
        else:
            g, g1, g2 = np.ones_like(t), np.zeros_like(t), np.zeros_like(t)
        out = [f * g]
        if nu >= 1:
            out.append((f1 * g)[..., None] * n + (f * g1)[..., None] * e)
        if nu >= 2:
            nn = n[..., :, None] * n[..., None, :]
            ne = n[..., :, None] * e[..., None, :]
            ee = e[..., :, None] * e[..., None, :]
            out.append((f2 * g)[..., None, None] * nn
                       + (f1 * g1)[..., None, None] * (ne + np.swapaxes(ne, -1, -2))
                       + (f * g2)[..., None, None] * ee)
        return out

    def basis(self, vertex, y, h, nu=0):
        """The candidate's full unscaled basis (..., MM) (+ derivatives): monomials up to
        poly, then the ridge slots (scaled by h^(deg - 1) of their slots)."""
        p0 = self.p0
        mm = monomials(y, 4, nu)
        rj = self.jet(vertex, y, nu)
        K = MM - p0
        scale = h[vertex][..., None] ** (DEG[p0:] - 1.0)
        out = []
        for k, (m, r) in enumerate(zip(mm, rj)):
            m = m.copy()
            tail = (slice(None),) * k          # the derivative axes after the slot axis
            sc = scale.reshape(scale.shape + (1,) * k)
            m[(Ellipsis, slice(p0, MM)) + tail] = r[(Ellipsis, slice(0, K)) + tail] * sc
            out.append(m)
        return out


def edge_dihedrals(topo, X):
    """(E,) degrees between the rest normals of the two faces of every edge (0 on borders)."""
    from gerbs_core.mesh.agreement import face_normals
    fn = face_normals(topo, X)
    ef = topo.edge_faces
    two = ef[:, 1] >= 0
    out = np.zeros(len(ef))
    out[two] = np.degrees(np.arccos(np.clip((fn[ef[two, 0]] * fn[ef[two, 1]]).sum(1), -1, 1)))
    return out


def find_ridges(topo, rings, X, opts, spiky=None):
    """The :class:`Ridges` of every vertex with a star edge sharper than opts["sharp"] degrees
    (opts: the options of :mod:`ridges`: sharp, sharp_max, quads, allow, poly, kind, merge,
    kmax, delta, dscale)."""
    V = topo.n_vertices
    p0 = n_monomials(opts["poly"])
    K = MM - p0
    e = np.asarray(topo.edges)
    dih = edge_dihedrals(topo, X)
    sharp = (dih > opts["sharp"]) & (dih < opts["sharp_max"])
    if opts["quads"]:    # edges between two quads only
        ef = topo.edge_faces
        fs = topo.face_sizes
        sharp &= (ef[:, 1] >= 0) & (fs[ef[:, 0]] == 4) & (fs[np.maximum(ef[:, 1], 0)] == 4)
    at = np.full(V, -1)
    ns, es, ds = [], [], []
    cosm = np.cos(np.radians(opts["merge"]))
    for v in range(V):
        if spiky is not None and not spiky[v]:
            continue
        if opts["allow"] is not None and not opts["allow"][v]:
            continue
        ks = np.flatnonzero(((e[:, 0] == v) | (e[:, 1] == v)) & sharp)
        if not len(ks):
            continue
        ks = ks[np.argsort(-dih[ks])]
        s0, s1 = rings.offsets[v], rings.offsets[v + 1]
        lines = []
        for k in ks:
            w = e[k, 0] + e[k, 1] - v
            hit = np.flatnonzero((rings.ids[s0:s1] == w) & (rings.ring[s0:s1] == 1))
            if not len(hit):
                continue
            yw = rings.y[s0 + hit[0]]
            L = np.hypot(*yw)
            u = yw / L
            # a line parallel to one kept already adds nothing (half ridges: same direction)
            dup = any((abs(u @ k0) if opts["kind"] == "line" else u @ k0) > cosm
                      for k0, _ in lines)
            if not dup and len(lines) < min(K, opts["kmax"]):
                lines.append((u, L))
        if not lines:
            continue
        at[v] = len(ns)
        n = np.zeros((K, 2))
        ee = np.zeros((K, 2))
        d = np.zeros(K)
        for j, (u, L) in enumerate(lines):
            ee[j] = u
            n[j] = (-u[1], u[0])
            width = {"edge": L, "h": rings.h[v], "min": min(L, rings.h[v])}[opts["dscale"]]
            d[j] = opts["delta"] * width
        ns.append(n)
        es.append(ee)
        ds.append(d)
    if not ns:
        return None
    return Ridges(at, np.array(ns), np.array(es), np.array(ds), p0, opts["kind"])


def _metric_inverse(N, p0, g):
    """Truncated pseudo-inverses (K, MM, MM) in the metric blockdiag(bending_gram(poly), g I)."""
    poly = {2: 1, 5: 2, 9: 3}[p0]
    G = np.eye(MM) * g
    G[:p0, :p0] = bending_gram(poly)
    L = np.linalg.cholesky(G)
    Li = np.linalg.inv(L)
    Nz = Li @ N @ Li.T
    lam, Q = np.linalg.eigh(Nz)
    top = lam[..., -1:]
    inv = np.where(lam > RCOND * np.maximum(top, 1e-300), 1.0 / np.where(lam > 0, lam, 1.0), 0.0)
    return Li.T @ ((Q * inv[..., None, :]) @ np.swapaxes(Q, -1, -2)) @ Li


def ridge_candidates(topo, charts, corners2d, rings, rd, kappa, metric):
    """The ridge candidate (CandidateFits, degree 4 layout) of the vertices with ridges: rings
    1-2 (weights 1 / |y|^2) plus the cage samples of spread_fits at total weight ``kappa``;
    ``metric`` the weight of the ridge slots in the pseudo-inverse's metric."""
    V = topo.n_vertices
    verts = np.flatnonzero(rd.at >= 0)
    K = len(verts)
    od, yd, ids, wd = spf._ring_rows(rings, verts, 2, MM)
    parts = [(od, yd, ids[:, None], np.ones((len(ids), 1)), wd)]
    if kappa:
        oc, yc, tv, tw, wc = spf._cage_rows(topo, charts, corners2d, verts, rings.h)
        parts.append((oc, yc, tv, tw, kappa * wc))
    J = max(p[2].shape[1] for p in parts)
    owner = np.concatenate([p[0] for p in parts])
    ys = np.concatenate([p[1] for p in parts])
    tcol = np.concatenate([np.pad(p[2], ((0, 0), (0, J - p[2].shape[1]))) for p in parts])
    tval = np.concatenate([np.pad(p[3], ((0, 0), (0, J - p[3].shape[1]))) for p in parts])
    w = spf._per_owner(np.concatenate([p[4] for p in parts]), owner, K)
    order = np.argsort(owner, kind="stable")
    owner, ys, w, tcol, tval = owner[order], ys[order], w[order], tcol[order], tval[order]
    n = len(owner)
    h = rings.h[verts][owner]
    # scaled basis: unscaled / h^deg
    B = rd.basis(verts[owner], ys * h[:, None], rings.h)[0] / h[:, None] ** DEG
    bw = B * w[:, None]
    starts = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
    N = np.add.reduceat((bw[:, :, None] * B[:, None, :]).reshape(n, MM * MM), starts).reshape(K, MM, MM)
    Pinv = _metric_inverse(N, rd.p0, metric)
    A = np.einsum("kmn,kn->km", Pinv[owner], bw) / h[:, None] ** DEG
    T = sp.csr_matrix((np.concatenate([tval.ravel(), -np.ones(n)]),
                       (np.concatenate([np.repeat(np.arange(n), J), np.arange(n)]),
                        np.concatenate([tcol.ravel(), verts[owner]]))), shape=(n, V))
    r = (verts[owner][:, None] * MM + np.arange(MM)).ravel()
    k = np.repeat(np.arange(n), MM)
    out = []
    for val in (A, bw):
        m = sp.csr_matrix((val.ravel(), (r, k)), shape=(V * MM, n)) @ T
        m.eliminate_zeros()
        out.append(m.tocsr())
    normal = np.zeros((V, MM, MM))
    normal[verts] = N
    return CandidateFits(4, out[0], normal, out[1])
