"""Side-independent local functions along crease chains (curve constraints).

On a cut crease edge ab (:mod:`gerbs_core.mesh.creases`) only Psi_a and Psi_b are
non-zero, and the partition is the same from both sides (fixed end-line scales), so
the two sides of the crease agree if every copy of a has the same local function
ON the crease ray. For each chain through a, a *curve local function*

    h_a(s) = X_a + sum_{k=1..d} h_k s^k,    s the signed arc length along the chain's rest edges,

is fitted (pinned least squares, weights 1 / s^2) to the chain neighbours within
``REACH`` steps (not past corners; a one-edge chain gives the straight segment),
and every copy's l_a is constrained on its crease rays (unit chart direction e,
toward the next vertex of the chain: h_a(r), toward the previous one: h_a(-r)):

    sum_{|m| = k} c_m e^m = h_k  (or (-1)^k h_k),   k = 1 .. deg l_a   (h_k = 0 beyond d).

The crease curve on ab is then Psi_a h_a + Psi_b h_b, a GERBS curve through the chain's
vertices (paper, Lemma 3), C-infinity along the chain (at a chain-interior vertex the
chart is straightened, so both rays of the chain carry one constraint and the tangent
plane stays regular).

The constraints are imposed by the constrained least-squares correction

    c <- c - Q K^T (K Q K^T)^+ (K c - g(X)),

Q the inverse of the vertex's (pinned, coupled) normal matrix: linear in (c, X), so
:class:`gerbs_core.mesh.coupling.CoupledFits` applies it after its first fit and after
every sweep and the coefficients stay a fixed sparse linear map of the positions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .creases import CORNER, FULL
from .monomials import monomial_exponents, n_monomials

__all__ = ["CurveConstraints", "curve_constraints", "curve_arms", "corner_scales", "HDEG",
           "REACH", "THROUGH", "crease_rays"]

HDEG = 3       # the highest degree of a curve local function
REACH = 2      # chain neighbours on each side used by a curve fit


@dataclass(frozen=True)
class CurveConstraints:
    """``K`` (NC, V MMAX) constraint rows on the coefficients, ``G`` (NC, V) their targets
    (g = G X), ``copy`` (NC,) the copy each row constrains (sparse csr)."""

    K: sp.csr_matrix
    G: sp.csr_matrix
    copy: np.ndarray

    def projection(self, normals, h, degrees, mmax):
        """(R (V MMAX, NC), K, G): c <- c - R (K c - G X) is the constrained least-squares
        correction in the metric of the normal matrices ``normals`` (V, MMAX, MMAX) (scaled
        coordinates y / h, zero-padded to each vertex's degree).

        Computed in a null-space basis of K (SVD), so K c = g holds to rounding even where
        the metric is nearly singular (copies with one face): c = c_p + P (c - c_p) with
        c_p = K^+ g and P = Z (Z^T N Z)^-1 Z^T N the N-orthogonal projection onto null(K),
        i.e. R = D (I - P) K_s^+ (D = h^-|m| the unscaling, K_s = K D). Dependent rows (two
        rays of different chains antiparallel in the chart) are met in least squares."""
        V = len(degrees)
        deg = monomial_exponents(int(round((np.sqrt(9 + 8 * mmax) - 3) / 2))).sum(1)
        Kd = self.K.tocsr()
        rows, cols, vals = [], [], []
        for v in np.unique(self.copy).tolist():
            sel = np.flatnonzero(self.copy == v)
            M = n_monomials(int(degrees[v]))
            D = h[v] ** -deg[:M].astype(float)
            Ks = Kd[sel][:, v * mmax:v * mmax + M].toarray() * D[None, :]
            N = normals[v, :M, :M]
            N = N + 1e-9 * max(np.trace(N) / M, 1e-300) * np.eye(M)
            U, sig, Wt = np.linalg.svd(Ks)
            r = int(np.sum(sig > 1e-10 * sig[0]))
            Kp = Wt[:r].T @ ((U[:, :r] / sig[:r]).T)          # K_s^+ (M, nc)
            Z = Wt[r:].T
            P = Z @ np.linalg.solve(Z.T @ N @ Z, Z.T @ N) if Z.shape[1] else np.zeros((M, M))
            R = D[:, None] * ((np.eye(M) - P) @ Kp)
            r_, c_ = np.nonzero(R)
            rows.append(v * mmax + r_)
            cols.append(sel[c_])
            vals.append(R[r_, c_])
        nc = self.K.shape[0]
        cat = (lambda a: np.concatenate(a)) if rows else (lambda a: np.zeros(0))
        R = sp.csr_matrix((cat(vals), (cat(rows).astype(np.int64), cat(cols).astype(np.int64))),
                          shape=(V * mmax, nc))
        return R, Kd, self.G.tocsr()


THROUGH = np.radians(150.0)   # two arms at a corner this straight share one curve


def _arm_of_edge(cut):
    """{cut edge: (chain, i)}: edge i of a chain joins its positions i and i + 1."""
    return {e: (k, i) for k, (_, es, _) in enumerate(cut.chains) for i, e in enumerate(es.tolist())}


def _ray_arm(cut, where, copy, he):
    """The arm (chain, position, step +1 / -1) of a copy's crease ray along half-edge he, or
    None if the ray's edge is not cut."""
    e = cut.original.halfedge_edge[he]
    if not cut.cut[e]:
        return None
    k, i = where[e]
    vs = cut.chains[k][0]
    return (k, i, 1) if vs[i] == cut.copy_of[copy] else (k, (i + 1) % len(vs), -1)


def _copy_rays(cut, charts=None):
    """Per boundary copy: [(half-edge, chart angle or None, arm or None)] of its start and
    end rays."""
    T = cut.topology
    so, sc = T.star_offsets, T.star_corners
    where = _arm_of_edge(cut)
    out = {}
    for c in np.flatnonzero(T.vertex_is_boundary).tolist():
        first, last = sc[so[c]], sc[so[c + 1] - 1]
        end = None if charts is None else charts.scale[c] * charts.span[c]
        out[c] = [(first, 0.0, _ray_arm(cut, where, c, first)),
                  (T.corner_prev[last], end, _ray_arm(cut, where, c, T.corner_prev[last]))]
    return out


def _arm_vertex(cut, arm):
    k, pos, _ = arm
    return int(cut.chains[k][0][pos])


def _arm_direction(cut, arm, X):
    k, pos, step = arm
    vs, _, closed = cut.chains[k]
    b = vs[(pos + step) % len(vs)]
    d = X[b] - X[vs[pos]]
    return d / np.linalg.norm(d)


def curve_arms(cut, X):
    """{arm: (curve, orientation)} and the curves (lists of 1 or 2 arms): the arms of one
    chain through a chain-interior vertex form one curve (its two sides), a chain end one
    curve, and at a corner of three or more cut edges two arms whose first edges make an
    angle above THROUGH (150 degrees; greedily, straightest first) share one curve -- the
    crease continues smoothly through the corner, e.g. a T-junction's bar; a linear part
    cannot give two antiparallel rays two different tangents. At a vertex crease of 1 the
    user asked for a corner: no arms are paired there."""
    arms_at = {}
    for k, (vs, _, closed) in enumerate(cut.chains):
        n = len(vs)
        for pos in range(n):
            for step in (1, -1):
                if closed or 0 <= pos + step < n:
                    arms_at.setdefault(int(vs[pos]), []).append((k, pos, step))
    curves, of = [], {}
    for a, arms in arms_at.items():
        if cut.corner[a] and cut.vertex_weight[a] >= FULL:
            todo = [[arm] for arm in arms]
        elif not cut.corner[a]:
            groups = {}
            for arm in arms:
                groups.setdefault((arm[0], arm[1]), []).append(arm)
            todo = [sorted(g, key=lambda t: -t[2]) for g in groups.values()]
        else:
            dirs = [_arm_direction(cut, arm, X) for arm in arms]
            pairs = sorted((float(dirs[i] @ dirs[j]), i, j) for i in range(len(arms))
                           for j in range(i + 1, len(arms)))
            free, todo = set(range(len(arms))), []
            for cos, i, j in pairs:
                if cos < np.cos(THROUGH) and i in free and j in free:
                    todo.append([arms[i], arms[j]])
                    free -= {i, j}
            todo += [[arms[i]] for i in sorted(free)]
        for group in todo:
            for o, arm in enumerate(group):
                of[arm] = (len(curves), 1 if o == 0 else -1)
            curves.append(group)
    return of, curves


def corner_scales(cut, angles, X, scale):
    """Chart scales (V',): ``scale`` (nan: the boundary rule's), and for CORNER copies bounded
    by two crease rays: pi / T where both rays belong to one curve (:func:`curve_arms`, the
    chart straightened like a chain vertex's), else the chart angle between the rays set to
    the 3D angle theta between their first edges (2 pi - theta where the fan spans more than
    pi), kept at least 30 degrees from pi and 15 from 0 and 2 pi. Why: l_a takes the two
    curves' tangents on its two rays, which determines its linear part; with the angles kept,
    a fan spanning pi (the two side faces at a box corner) puts the rays antiparallel while
    their tangents are not, and no linear part exists (measured: a 0.5 gap on a box whose
    top loop has corners). ``angles`` (C,): the layouts' corner angles."""
    T = cut.topology
    out = np.array(scale, dtype=np.float64)
    span = np.bincount(T.face_vertices, angles, minlength=T.n_vertices)
    of, _ = curve_arms(cut, X)
    lo, gap = np.radians(15.0), np.radians(30.0)
    for c, rays in _copy_rays(cut).items():
        (_, _, a1), (_, _, a2) = rays
        if cut.role[c] != CORNER or a1 is None or a2 is None:
            continue
        if of[a1][0] == of[a2][0]:
            out[c] = np.pi / span[c]
            continue
        u, w = _arm_direction(cut, a1, X), _arm_direction(cut, a2, X)
        theta = np.arccos(np.clip(u @ w, -1.0, 1.0))
        phi = theta if span[c] <= np.pi else 2.0 * np.pi - theta
        phi = np.clip(phi, lo, np.pi - gap) if phi <= np.pi else np.clip(phi, np.pi + gap,
                                                                        2 * np.pi - lo)
        out[c] = phi / span[c]
    return out


def _curve_fit(cut, arms, X, degree, reach=REACH):
    """Rows W (d, n) and data vertices (n,) of h_1..h_d of the curve made of ``arms`` (the
    first arm at s > 0, the second at s < 0): h_k = sum_j W[k-1, j] (X[ids[j]] - X[a]);
    d = min(degree, number of data). Data: up to ``reach`` chain steps along each arm, not
    past the chain's ends; on short loops every vertex once."""
    idx, s = [], []
    a = None
    for o, (k, pos, step) in zip((1.0, -1.0), arms):
        vs, _, closed = cut.chains[k]
        n = len(vs)
        a = vs[pos]
        length = 0.0
        for t in range(1, reach + 1):
            j = pos + step * t
            if not closed and not 0 <= j < n:
                break
            prev, cur = vs[(j - step) % n], vs[j % n]
            length += float(np.linalg.norm(X[cur] - X[prev]))
            if cur == a or cur in idx:       # a short loop: every neighbour once
                break
            idx.append(cur)
            s.append(o * length)
    s = np.array(s)
    d = min(degree, len(s))
    scale = np.abs(s).mean()
    t = s / scale
    A = t[:, None] ** np.arange(1, d + 1)[None, :]
    w = 1.0 / t ** 2
    W = np.linalg.solve(A.T @ (w[:, None] * A), (A * w[:, None]).T)
    W /= scale ** np.arange(1, d + 1)[:, None]
    return W, np.array(idx, dtype=np.int64), a, d


def crease_rays(cut, charts, of):
    """Crease rays of every copy: a list of (copy, unit chart direction e (2,), curve,
    orientation): the ray carries h(r) (orientation +1) or h(-r) (-1). Two rays of one
    curve at a copy (a straightened or dart chart: antiparallel with opposite orientations,
    or coincident) are one constraint: only the first is listed."""
    out = []
    for c, rays in _copy_rays(cut, charts).items():
        seen = set()
        for _, ang, arm in rays:
            if arm is None:
                continue
            curve, o = of[arm]
            if curve in seen:
                continue
            seen.add(curve)
            out.append((c, np.array([np.cos(ang), np.sin(ang)]), curve, o))
    return out


def curve_constraints(cut, charts, X, degrees, mmax) -> CurveConstraints | None:
    """The curve constraints of every crease ray (module docstring) on the cut mesh's copies
    with local degrees ``degrees`` (V',), rest positions X (V, 3) of the ORIGINAL vertices;
    targets G act on the copies' positions (copies [0, V) are the original vertices)."""
    of, curves = curve_arms(cut, X)
    rays = crease_rays(cut, charts, of)
    if not rays:
        return None
    V = len(cut.copy_of)
    E = monomial_exponents(int(round((np.sqrt(9 + 8 * mmax) - 3) / 2)))
    order = E.sum(1)
    # a curve's degree: at most every constrained copy's degree
    dmin = {}
    for c, _, k, _ in rays:
        dmin[k] = min(dmin.get(k, HDEG), int(degrees[c]))
    # a curve ending at a corner leaves it along its first edge (reach 1: h = the chord's
    # line), as Catmull-Clark's corner rule does: the crease turns by the mesh's angle there
    fits = {k: _curve_fit(cut, curves[k], X, d,
                          1 if len(curves[k]) == 1 and cut.corner[_arm_vertex(cut, curves[k][0])]
                          else REACH) for k, d in dmin.items()}
    kr, kc, kv, gr, gc, gv, cp = [], [], [], [], [], [], []
    row = 0
    for c, e, k, sign in rays:
        W, ids, a, d = fits[k]
        mono = e[0] ** E[:, 0] * e[1] ** E[:, 1]
        for q in range(1, int(degrees[c]) + 1):
            m = np.flatnonzero(order == q)
            kr.append(np.full(len(m), row)), kc.append(c * mmax + m), kv.append(mono[m])
            if q <= d:
                f = float(sign) ** q
                gr.append(np.full(len(ids) + 1, row))
                gc.append(np.append(ids, a))
                gv.append(f * np.append(W[q - 1], -W[q - 1].sum()))
            cp.append(c)
            row += 1
    cat = np.concatenate
    K = sp.csr_matrix((cat(kv), (cat(kr), cat(kc))), shape=(row, V * mmax))
    G = sp.csr_matrix((cat(gv), (cat(gr), cat(gc))) if gr else ([], ([], [])), shape=(row, V))
    return CurveConstraints(K, G, np.array(cp, dtype=np.int64))
