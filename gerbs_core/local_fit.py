"""Local functions l_v of the blending surface: weighted least squares in chart v (DESIGN 5).

l_v(y) = X_v + sum_m c_{v,m} y^m over the monomials y^m of total degree 1..d
(d = 0..3) in chart coordinates y, so l_v(0) = X_v exactly. The coefficients
minimise sum_j w_j |l_v(y_j) - X_j|^2 over data points j: the chart positions of
the 1-ring and of the far corners of the incident faces, and, when there are
fewer than max(7, M + 2) data (M the number of unknown coefficients) or the
scaled fit's condition number exceeds ``max_condition`` (about 100), the corners
of up to two more layers of faces beyond the link, unfolded isometrically across
the far edges into the sector's frame and then angle-scaled like the chart.
(Measured on a prototype: the plain interpolation with as many data as unknowns
is ill-conditioned, up to 6.6e4, and Tikhonov's minimum-norm answer with fewer
data is the wrong quadratic; both stop convergence.)

The fit is linear in the vertex positions: c_v = A_v (X_{N_v} - X_v), where A_v
(M, N_v) depends only on the charts (mode "regular": only on topology). Weights
w_j = (h / |y_j|)^2, h = mean chart radius of the first data layer.
Degree 1 fits are exact for linear data, degree 2 for quadratics, ... whenever
the charts are isometric images of a flat layout (flat metric mesh, rule keep).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InvalidParameterError

__all__ = ["LocalFits", "fit_local_functions", "monomials", "monomial_exponents"]

RCOND = 1e-10  # relative singular-value cut-off of the least-squares solves


def monomial_exponents(degree: int) -> np.ndarray:
    """Exponents (M, 2) of the monomials of total degree 1..degree, graded order."""
    return np.array([(k - j, j) for k in range(1, degree + 1) for j in range(k + 1)],
                    dtype=np.int64).reshape(-1, 2)


def monomials(y: np.ndarray, degree: int, nu: int = 0):
    """Monomials y1^a y2^b (1 <= a+b <= degree) and derivatives, vectorized.

    y (..., 2). Returns [m (..., M), dm (..., M, 2), d2m (..., M, 2, 2)] up to nu.
    Exact.
    """
    y = np.asarray(y, dtype=np.float64)
    E = monomial_exponents(degree)
    M = len(E)
    p1 = [np.ones(y.shape[:-1])]
    p2 = [np.ones(y.shape[:-1])]
    for _ in range(degree):
        p1.append(p1[-1] * y[..., 0])
        p2.append(p2[-1] * y[..., 1])

    def pw(p, k):
        return p[k] if k >= 0 else np.zeros(y.shape[:-1])

    out = [np.stack([p1[a] * p2[b] for a, b in E], axis=-1) if M else np.zeros(y.shape[:-1] + (0,))]
    if nu >= 1:
        d = np.zeros(y.shape[:-1] + (M, 2))
        for i, (a, b) in enumerate(E):
            if a:
                d[..., i, 0] = a * pw(p1, a - 1) * p2[b]
            if b:
                d[..., i, 1] = b * p1[a] * pw(p2, b - 1)
        out.append(d)
    if nu >= 2:
        h = np.zeros(y.shape[:-1] + (M, 2, 2))
        for i, (a, b) in enumerate(E):
            if a >= 2:
                h[..., i, 0, 0] = a * (a - 1) * p1[a - 2] * p2[b]
            if b >= 2:
                h[..., i, 1, 1] = b * (b - 1) * p1[a] * p2[b - 2]
            if a and b:
                h[..., i, 0, 1] = h[..., i, 1, 0] = a * b * p1[a - 1] * p2[b - 1]
        out.append(h)
    return out


@dataclass(frozen=True)
class LocalFits:
    """Linear local fits of all vertices, padded.

    ids (V, N) int, -1 = padding; coef (V, M, N): c_v = sum_j coef[v, :, j]
    (X[ids[v, j]] - X[v]); n_data (V,); layers (V,) extra face layers used;
    cond (V,) condition number of the scaled weighted fit; degree; coef_flat (V, M, N)
    the fit without linear terms (Hermite normals), None unless fitted with flat=True.
    """

    ids: np.ndarray
    coef: np.ndarray
    n_data: np.ndarray
    layers: np.ndarray
    cond: np.ndarray
    degree: int
    coef_flat: np.ndarray | None = None

    def coefficients(self, X: np.ndarray, normals: np.ndarray | None = None) -> np.ndarray:
        """Polynomial coefficients (V, M, k) of l_v for vertex data X (V, k).

        normals (V, 3) (optional, unit, with k = 3): Hermite data: the linear part
        of l_v is tangent to the plane normal to n_v. Tangential components are
        the plain fit; the normal component is the least-squares fit without
        linear terms (``coef_flat``), so the result is optimal under the constraint.
        """
        X = np.asarray(X, dtype=np.float64)
        Xp = np.concatenate([X, np.zeros((1,) + X.shape[1:])])
        D = Xp[self.ids] - X[:, None]  # (V, N, k); padding has coef 0
        C = np.einsum("vmn,vnk->vmk", self.coef, D)
        if normals is None or self.degree == 0:
            return C
        if self.coef_flat is None:
            raise InvalidParameterError("normals", "these fits were made with flat=False; "
                                        "Hermite normals need fit_local_functions(..., flat=True)")
        n = np.asarray(normals, dtype=np.float64)
        C0 = np.einsum("vmn,vnk->vmk", self.coef_flat, D)  # linear rows are 0
        Cn = np.einsum("vmk,vk->vm", C, n)
        C0n = np.einsum("vmk,vk->vm", C0, n)
        return C + (C0n - Cn)[:, :, None] * n[:, None, :]


def _to_chart(z: np.ndarray, theta_ref: np.ndarray, s) -> np.ndarray:
    """Unfolded complex points z -> chart points, angle continuous about theta_ref.
    Elementwise (theta_ref and the angle scale s broadcast against z)."""
    th = theta_ref + np.angle(z * np.exp(-1j * theta_ref))
    r = np.abs(z)
    return np.stack([r * np.cos(s * th), r * np.sin(s * th)], axis=-1)


def fit_local_functions(topo, charts, corners2d: np.ndarray, degree: int = 2,
                        max_condition: float = 100.0, max_layers: int = 2,
                        flat: bool = True) -> LocalFits:
    """Fit l_v for every vertex (see the module docstring). Exact linear algebra via SVD.

    topo: a MeshTopology-like object with face_offsets, face_vertices,
    star_offsets, star_corners, halfedge_twin (C,) (opposite half-edge or -1).
    charts: :class:`gerbs_core.charts.VertexCharts`. flat: also compute
    ``coef_flat`` (needed only for Hermite normals; else it is None).

    Vectorized: the first data layer of all vertices is collected at once, equal
    layouts share one solve (exact dict on the rounded layout), and the solves of
    equally sized layouts run as one batched SVD; only the vertices needing
    enlargement take the per-face unfolding loop.
    """
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) \
            or not 0 <= degree <= 3:
        raise InvalidParameterError("degree", f"must be an integer in 0..3, got {degree!r}")
    degree = int(degree)
    off = np.asarray(topo.face_offsets)
    fv = np.asarray(topo.face_vertices)
    V = len(topo.star_offsets) - 1
    E = monomial_exponents(degree)
    M = len(E)
    if degree == 0:
        return LocalFits(np.full((V, 1), -1), np.zeros((V, 0, 1)), np.zeros(V, int),
                         np.zeros(V, int), np.ones(V), 0)
    twin = np.asarray(topo.halfedge_twin)
    sizes = np.diff(off)
    corner_face = np.repeat(np.arange(len(sizes)), sizes)
    so, sc = np.asarray(topo.star_offsets), np.asarray(topo.star_corners)
    zc = corners2d[:, 0] + 1j * corners2d[:, 1]
    # unfolded positions (complex) of all corners of each corner's face, in the frame
    # of that corner's vertex chart, precomputed for all corners at once
    nmax = int(sizes.max())
    zall = np.zeros((len(fv), nmax), dtype=complex)
    yall = np.zeros((len(fv), nmax, 2))
    for n in np.unique(sizes):
        cs_n = np.flatnonzero(sizes[corner_face] == n)
        idx = off[corner_face[cs_n]][:, None] + np.arange(n)[None, :]
        r, th = charts.unfolded(np.broadcast_to(cs_n[:, None], idx.shape), corners2d[idx])
        zall[cs_n, :n] = r * np.exp(1j * th)
        # chart positions of the star faces' corners: angle theta is continuous in the sector
        s_c = charts.scale[fv[cs_n]][:, None]
        yall[cs_n, :n] = np.stack([r * np.cos(s_c * th), r * np.sin(s_c * th)], axis=-1)
    tref_all = charts.theta0 + 0.5 * charts.alpha
    min_data = max(7, M + 2)
    deg_of = E.sum(axis=1)

    # first layer, all vertices at once: the corners of the star faces in star order,
    # each vertex once (first occurrence), v itself excluded
    star_v = np.repeat(np.arange(V), np.diff(so))
    ec = np.repeat(sc, sizes[corner_face[sc]])  # star corner of every entry
    ev = np.repeat(star_v, sizes[corner_face[sc]])
    start = np.repeat(off[corner_face[sc]], sizes[corner_face[sc]])
    ei = np.arange(len(ec)) - np.repeat(np.cumsum(sizes[corner_face[sc]])
                                        - sizes[corner_face[sc]], sizes[corner_face[sc]])
    eq = fv[start + ei]
    _, first = np.unique(ev * V + eq, return_index=True)  # first occurrence per (v, q)
    first = np.sort(first)
    first = first[eq[first] != ev[first]]
    ids0 = eq[first]
    n0 = np.bincount(ev[first], minlength=V)
    o0 = np.zeros(V + 1, dtype=np.int64)
    np.cumsum(n0, out=o0[1:])
    Y0 = yall[ec[first], ei[first]]

    cache = {}  # equal data layouts (e.g. mode regular) share one solve
    Ys = [Y0[o0[v]:o0[v + 1]] for v in range(V)]
    n0l = n0.tolist()
    fit = _fits_cached(cache, Ys, n0l, E, deg_of, flat)
    ids_l = [ids0[o0[v]:o0[v + 1]].tolist() for v in range(V)]
    layers = [0] * V

    def ok(v):
        return ((len(Ys[v]) >= min_data and fit[v][0] <= max_condition)
                or layers[v] >= max_layers)

    todo = [v for v in range(V) if not ok(v)]
    if todo:
        sc_l, so_l, cf_l = sc.tolist(), so.tolist(), corner_face.tolist()
        off_l, twin_l = off.tolist(), twin.tolist()
        fv_l = fv.tolist()
        face_v = [fv_l[a:b] for a, b in zip(off_l[:-1], off_l[1:])]
        state, stuck = {}, set()
        for v in todo:
            star = sc_l[so_l[v]:so_l[v + 1]]
            placed = {cf_l[c]: (zall[c, :sizes[cf_l[c]]], tref_all[c]) for c in star}
            state[v] = (placed, [cf_l[c] for c in star], set(ids_l[v]) | {v})
        while todo:
            zs, trefs, svs, counts = [], [], [], []  # new points of this layer, all vertices
            for v in todo:
                placed, frontier, seen = state[v]
                ids, s = ids_l[v], charts.scale[v]
                new_frontier, n_before = [], len(zs)
                # one more layer of faces across the outer edges of the placed faces
                for f in frontier:
                    z, tref = placed[f]
                    for k, q in enumerate(range(off_l[f], off_l[f + 1])):
                        t = twin_l[q]
                        if t < 0:
                            continue
                        g = cf_l[t]
                        if g in placed:
                            continue
                        # corner t of g sits at vertex of next(q), next(t) at vertex of q
                        za = z[(k + 1) % len(z)]
                        zb = z[k]
                        gs = np.arange(off_l[g], off_l[g + 1])
                        nt = off_l[g] + (t - off_l[g] + 1) % len(gs)
                        rot = (zb - za) / (zc[nt] - zc[t])
                        rot /= abs(rot)
                        zg = za + (zc[gs] - zc[t]) * rot
                        placed[g] = (zg, tref)
                        new_frontier.append(g)
                        for i, qv in enumerate(face_v[g]):
                            if qv not in seen:
                                seen.add(qv)
                                ids.append(qv)
                                zs.append(zg[i])
                                trefs.append(tref)
                layers[v] += 1
                state[v] = (placed, new_frontier, seen)
                svs.extend([s] * (len(zs) - n_before))
                counts.append(len(zs) - n_before)
                if not new_frontier:
                    stuck.add(v)  # nothing left to add: keep this fit
            # chart positions of the layer's new points, one elementwise call for all
            Yn = _to_chart(np.array(zs, dtype=complex), np.array(trefs, dtype=np.float64),
                           np.array(svs, dtype=np.float64))
            at = 0
            for v, cnt in zip(todo, counts):
                if cnt:
                    Ys[v] = np.concatenate([Ys[v], Yn[at:at + cnt]])
                    at += cnt
            fits = _fits_cached(cache, [Ys[v] for v in todo], [n0l[v] for v in todo],
                                E, deg_of, flat)
            for v, f in zip(todo, fits):
                fit[v] = f
            todo = [v for v in todo if not ok(v) and v not in stuck]
    N = max(max(len(i) for i in ids_l), 1)
    ids = np.full((V, N), -1, dtype=np.int64)
    coef = np.zeros((V, M, N))
    coef0 = np.zeros((V, M, N)) if flat else None
    n_data = np.array([len(i) for i in ids_l], dtype=np.int64)
    cnd = np.array([f[0] for f in fit], dtype=np.float64)
    for v in range(V):
        i = ids_l[v]
        ids[v, :len(i)] = i
        coef[v, :, :len(i)] = fit[v][1]
        if flat:
            coef0[v, :, :len(i)] = fit[v][2]
    return LocalFits(ids, coef, n_data, np.array(layers, dtype=np.int64), cnd, degree, coef0)


def _fits_cached(cache, Ys, n0s, E, deg_of, flat):
    """[(cond, A, A0)] for the layouts Ys [(N_i, 2)] with first-layer sizes n0s: one
    solve per distinct (n0, rounded layout) (``cache``), batched by shape."""
    # one rounding for all layouts (np.round per small array costs ~10 us)
    o = np.cumsum([0] + [len(Y) for Y in Ys])
    R = np.round(np.concatenate(Ys), 12) if len(Ys) else np.zeros((0, 2))
    keys = [(n0, R[a:b].tobytes()) for n0, a, b in zip(n0s, o[:-1].tolist(), o[1:].tolist())]
    todo = {}
    for key, Y, n0 in zip(keys, Ys, n0s):
        if key not in cache and key not in todo:
            todo[key] = (Y, n0)
    by_shape = {}
    for key, (Y, n0) in todo.items():
        by_shape.setdefault((len(Y), n0), []).append(key)
    for (n, n0), ks in by_shape.items():
        res = _weighted_fits(np.stack([todo[k][0] for k in ks]), n0, E, deg_of, flat)
        cache.update(zip(ks, res))
    return [cache[k] for k in keys]


def _weighted_fits(Y, n0, E, deg_of, flat=True):
    """[(cond, A (M, N), A0 (M, N) or None)] of the weighted fits to data at chart
    points Y (G, N, 2) (a batch of layouts with first-layer size n0), by SVD."""
    G, N = Y.shape[:2]
    M = len(E)
    if not N:
        return [(np.inf, np.zeros((M, 0)), np.zeros((M, 0)))] * G
    h = np.mean(np.hypot(Y[:, :n0, 0], Y[:, :n0, 1]), axis=1) if n0 else np.ones(G)
    hh = h[:, None, None]
    sw = hh[:, :, 0] / np.hypot(Y[..., 0], Y[..., 1])  # sqrt of the weights (h/|y|)^2
    B = np.prod((Y[:, :, None, :] / hh[..., None]) ** E[None, None, :, :], axis=-1) * sw[..., None]
    U, S, Vt = np.linalg.svd(B, full_matrices=False)
    conds = np.where((N >= M) & (S[:, -1] > 0), S[:, 0] / np.where(S[:, -1] > 0, S[:, -1], 1.0),
                     np.inf)
    if not flat and np.all(S > RCOND * S[:, :1]):  # full rank: all solves in one batch
        A = ((Vt.transpose(0, 2, 1) / S[:, None, :]) @ U.transpose(0, 2, 1)) \
            * sw[:, None, :] / h[:, None, None] ** deg_of[None, :, None]
        return [(c, a, None) for c, a in zip(conds.tolist(), A)]
    out = []
    for j in range(G):
        s = S[j]
        cond = s[0] / s[-1] if N >= M and s[-1] > 0 else np.inf
        # A = diag(h^-deg) pinv(B) diag(sw); singular values below RCOND * S[0] are
        # dropped (rank-deficient data even after enlargement, e.g. a cubic from a few
        # collinear boundary points: the minimum-norm fit, instead of round-off
        # amplified by 1e16)
        keep = s > RCOND * s[0]
        A = ((Vt[j][keep].T / s[keep]) @ U[j][:, keep].T) * sw[j][None, :] / h[j] ** deg_of[:, None]
        out.append((cond, A, _flat_fit(B[j], sw[j], h[j], deg_of) if flat else None))
    return out


def _flat_fit(B, sw, h, deg_of):
    """The same weighted fit without the linear monomials (rows of degree 1 are 0)."""
    A0 = np.zeros((B.shape[1], B.shape[0]))
    hi = deg_of >= 2
    if hi.any():
        A0[hi] = np.linalg.pinv(B[:, hi], rcond=RCOND) * sw[None, :] / h ** deg_of[hi][:, None]
    return A0
