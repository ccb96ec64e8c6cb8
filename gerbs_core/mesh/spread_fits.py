"""Extra candidate fits at spread stars: local functions that also see the star's cage.

Where a vertex's cage star spreads (the largest angle between a star face's normal and
the vertex's mean normal above ``SPREAD`` degrees: Suzanne's ear rims and mouth corners,
the cow's hooves and horns) every data fit of :data:`gerbs_core.mesh.fits.CANDIDATES`
turns against some star face, and the blend folds there. The extra candidate of such a
vertex is the pinned degree-4 fit of rings 1-2 (weights 1 / |y|^2, as in
:mod:`gerbs_core.mesh.fits`) plus sample points of every star triangle and quad (a
lattice of resolution ``CAGE_RESOLUTION``, each face weighing the same) whose targets are their
points of the cage face (barycentric / bilinear in the corners), the two groups
weighted 1 : ``CAGE_WEIGHT``: a quartic that turns with the star's faces. Its targets
are linear in X and constants give zero coefficients, so the output stays a fixed
sparse linear function of the positions; it reads its data rings only (the locality
of :mod:`gerbs_core.mesh.coupling` holds).

The choice (:mod:`gerbs_core.mesh.agreement`) may take it only where its fold penalty
is below ``GATE`` times the least of the vertex's base candidates (:func:`gate`):
measured, offering it unconditionally let the choice trade folds for agreement (cow
pairs above 90 degrees 88 -> 94-110). Meshes without spread stars (spheres, tori,
height fields) get no extra candidate: their surfaces are bit-identical.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .arrays import ranges
from .fits import CandidateFits, pinned_normal_inverse
from .monomials import monomial_exponents, monomials, n_monomials

__all__ = ["SPREAD", "star_spread", "spread_faces", "spread_candidates", "gate"]

SPREAD = 60.0           # degrees: a star spreads above this (rule.spread overrides)
RULE = (4, 2)           # degree and data rings of the extra candidate
CAGE_WEIGHT = 1.0       # the cage samples' total weight against the ring data's
CAGE_RESOLUTION = 4     # lattice resolution of the cage samples of each star face
GATE = 0.5              # offered where its fold penalty < GATE x the base candidates' least


def star_spread(topo, X) -> np.ndarray:
    """(V,) degrees: the largest angle between a star face's normal and the vertex's mean
    normal (the normalised sum of its star faces' unit normals), positions X (V, 3)."""
    from .agreement import face_normals
    fn = face_normals(topo, X)
    cf, fv = topo.corner_face, topo.face_vertices
    vn = np.zeros((topo.n_vertices, 3))
    np.add.at(vn, fv, fn[cf])
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    ang = np.degrees(np.arccos(np.clip((vn[fv] * fn[cf]).sum(1), -1.0, 1.0)))
    out = np.zeros(topo.n_vertices)
    np.maximum.at(out, fv, ang)
    return out


def spread_faces(topo, star, spread: float) -> np.ndarray:
    """(F,) bool: the faces having a corner whose cage star spreads above ``spread``
    degrees, from the vertices' spreads ``star`` (V,) (:func:`star_spread`)."""
    hit = np.zeros(topo.n_faces, bool)
    hit[topo.corner_face[(np.asarray(star) > spread)[topo.face_vertices]]] = True
    return hit


def _ring_rows(rings, verts, layers, M):
    """Data rows of the vertices ``verts`` (K,): (owner (n,) in 0..K-1, y (n, 2) scaled,
    target vertex (n,), weight (n,) summing to 1 per owner); rings 1..layers, one ring
    more where they hold fewer than M + 2 data (the rule of mesh.fits)."""
    cnt = np.diff(rings.offsets)[verts]
    owner = np.repeat(np.arange(len(verts)), cnt)
    idx = ranges(rings.offsets[verts], cnt)
    n_in = np.bincount(owner[rings.ring[idx] <= layers], minlength=len(verts))
    use = rings.ring[idx] <= np.where(n_in < M + 2, layers + 1, layers)[owner]
    owner, idx = owner[use], idx[use]
    y = rings.y[idx] / rings.h[verts][owner, None]
    return owner, y, rings.ids[idx], _per_owner(1.0 / (y ** 2).sum(1), owner, len(verts))


def _per_owner(w, owner, K):
    """Weights w (n,) scaled to sum to 1 for every owner."""
    return w / np.bincount(owner, w, minlength=K)[owner]


def _cage_rows(topo, charts, corners2d, verts, h):
    """Cage rows of the vertices ``verts`` (K,): (owner (n,), y (n, 2) scaled, target
    vertices (n, k) and weights (n, k) (the sample's point of its cage face), weight (n,)
    summing to 1 per owner, each star face weighing the same). The samples at the
    vertex itself are left out (target X_v: the pin already gives it)."""
    from .lattice import Lattice
    lat = Lattice(topo, CAGE_RESOLUTION)
    x = lat.map_to_polygon(corners2d, local=True)
    cw = lat.corner_weights(local=True)
    lo = lat.local_offsets
    slot = np.full(topo.n_vertices, -1)
    slot[verts] = np.arange(len(verts))
    # triangles and quads only: an n-gon's cage point (a fan about its centre) reads all
    # its corners, and a cap's many samples made the Cylinder's build 4x slower
    cs = np.flatnonzero((slot[topo.face_vertices] >= 0) & (topo.face_sizes[topo.corner_face] <= 4))
    f = topo.corner_face[cs]
    cnt = lo[f + 1] - lo[f]
    row_c = np.repeat(cs, cnt)
    idx = ranges(lo[f], cnt)
    owner = slot[topo.face_vertices[row_c]]
    y = charts.to_chart(row_c, x[idx])[0] / h[verts][owner, None]
    keep = np.hypot(y[:, 0], y[:, 1]) > 1e-9
    kmax = min(4, cw.shape[1])
    fr = topo.corner_face[row_c]
    k = np.arange(kmax)
    tv = topo.face_vertices[np.minimum(topo.face_offsets[fr][:, None] + k,
                                       topo.face_offsets[fr + 1][:, None] - 1)]
    w = 1.0 / np.repeat(cnt, cnt).astype(np.float64)
    return (owner[keep], y[keep], tv[keep], cw[idx][keep][:, :kmax],
            _per_owner(w[keep], owner[keep], len(verts)))


def spread_candidates(topo, charts, corners2d, rings, X, spread: float = SPREAD, star=None):
    """(extra candidates (list of :class:`~gerbs_core.mesh.fits.CandidateFits`, empty
    where no star spreads), spread stars (V,) bool): the fit of the module docstring at
    every vertex whose star spreads above ``spread`` degrees, no rows elsewhere. ``star``
    (V,): the vertices' :func:`star_spread` when the caller has it already."""
    V = topo.n_vertices
    spiky = (star_spread(topo, X) if star is None else star) > spread
    if not spiky.any():
        return [], spiky
    verts = np.flatnonzero(spiky)
    K = len(verts)
    degree, layers = RULE
    M = n_monomials(degree)
    od, yd, ids, wd = _ring_rows(rings, verts, layers, M)
    oc, yc, tv, tw, wc = _cage_rows(topo, charts, corners2d, verts, rings.h)
    owner = np.concatenate([od, oc])
    y = np.concatenate([yd, yc])
    # 1 : CAGE_WEIGHT, summing to 1 per vertex (a star of n-gons only has no cage rows)
    w = _per_owner(np.concatenate([wd, CAGE_WEIGHT * wc]), owner, K)
    # targets: row k's is sum_j tval[k, j] X[tcol[k, j]] (a ring vertex, or a cage point)
    tcol = np.concatenate([np.pad(ids[:, None], ((0, 0), (0, tv.shape[1] - 1))), tv])
    tval = np.concatenate([np.pad(np.ones((len(ids), 1)), ((0, 0), (0, tv.shape[1] - 1))), tw])
    order = np.argsort(owner, kind="stable")          # rows grouped by vertex
    owner, y, w, tcol, tval = owner[order], y[order], w[order], tcol[order], tval[order]
    n = len(owner)
    B = monomials(y, degree)[0]                                   # (n, M)
    bw = B * w[:, None]
    starts = np.flatnonzero(np.r_[True, owner[1:] != owner[:-1]])
    N = np.add.reduceat((bw[:, :, None] * B[:, None, :]).reshape(n, M * M), starts)
    N = N.reshape(K, M, M)
    Pinv = pinned_normal_inverse(N, degree)
    deg = monomial_exponents(degree).sum(1)
    A = np.einsum("kmn,kn->km", Pinv[owner], bw) / rings.h[verts][owner, None] ** deg  # unscaled
    # row k's target minus the pin: sum_j tval[k, j] X[tcol[k, j]] - X_v (T @ X)
    J = tcol.shape[1]
    T = sp.csr_matrix((np.concatenate([tval.ravel(), -np.ones(n)]),
                       (np.concatenate([np.repeat(np.arange(n), J), np.arange(n)]),
                        np.concatenate([tcol.ravel(), verts[owner]]))), shape=(n, V))
    r = (verts[owner][:, None] * M + np.arange(M)).ravel()
    k = np.repeat(np.arange(n), M)
    out = []
    for val in (A, bw):     # c = val^T (T X): the coefficients, and the normal equations' rhs
        m = sp.csr_matrix((val.ravel(), (r, k)), shape=(V * M, n)) @ T
        m.eliminate_zeros()   # the padding slots (value 0, column 0) stay out of the sparsity
        out.append(m.tocsr())
    normal = np.zeros((V, M, M))
    normal[verts] = N
    return [CandidateFits(degree, out[0], normal, out[1])], spiky


def gate(penalty, vertex, n_extra: int, spiky) -> np.ndarray:
    """The fold penalty (SC, ncand) with the last ``n_extra`` (extra) candidates made
    unchoosable (infinite) at rows of vertices not in ``spiky`` (V,) and at vertices where
    their summed penalty is not below GATE x the least of the base candidates'."""
    if not n_extra:
        return penalty
    V = len(spiky)
    E = np.stack([np.bincount(vertex, penalty[:, i], minlength=V)
                  for i in range(penalty.shape[1])], 1)
    shut = ~spiky[:, None] | (E[:, -n_extra:] >= GATE * E[:, :-n_extra].min(1)[:, None])
    out = penalty.copy()
    out[:, -n_extra:][shut[vertex]] = np.inf
    return out
