"""Fairing: how sharply the surface may turn (the last step of the fair-shape rule).

S = sum_v Psi_v l_v equals l_v on a plateau around every vertex and turns from one local
function to the next inside the transitions; on a coarse cage with sharp features
(Suzanne's mouth corners and ears) the turn concentrates there into a few lattice
steps. The choice and coupling of :mod:`gerbs_core.mesh.agreement` make neighbouring local
functions agree; this step then bounds the turning itself. On the rest shape, on the
lattice of resolution ``rule.turn_resolution`` (one lattice for every output
resolution), the local functions' coefficients get a correction

    delta c_{v,m} = sum_{u in N(v)} a_{v,m,u} (X_u - X_v)       (m of degree <= deg v)

with the weights a minimising

    sum_{adjacent lattice triangles i, j} max(0, cos(turn) - n_i . n_j)^2
        + weight sum_{v,m} |h_v^(|m|-1) delta c_{v,m}|^2
        + stay sum_{lattice points p} |delta S(p)|^2 / area(f_p)

(n the unit normals of the lattice triangles of S -- the output's own triangulation at
that resolution, obtuse faces flipped --, h_v the star's scale, delta S(p) how far the
correction moves the point p of rest face f_p: every term is dimensionless, so the rule is
scale invariant). The last term (``rule.turn_stay``) keeps the correction from inflating a
thin part, which turns less when it is fatter: Blender's Cube scaled to a 4 x 0.5 x 0.2
plank came out 10x its thickness without it, 3.3x with it. The unknowns are the delta c of
the corners of the faces holding a pair beyond the bound and of their ring 1; they fall into
regions (connected in ring 1), each optimised alone by L-BFGS (scipy) over every pair of
lattice triangles it can change (run again, up to ``RESTARTS`` times, while the region
still has a pair beyond 90 degrees), one region after another on the points the previous
ones left, and kept only where it turns its pairs less than before (a smaller sum of squared
excesses and no more pairs beyond 60 or 90 degrees: a region where the optimisation does
not settle, e.g. among slivers, stays as it was). Each delta c is then written as the
least-norm combination a of v's offsets over N(v): ring 1, or rings 1-2 where ring 1 is
flat (an inset face's corners: ring-1 offsets in one plane cannot carry a correction
across it), exact where they span R^3 (every star of a manifold cage but a flat disc).

The first term is zero unless two neighbouring triangles meet at more than ``rule.turn``
degrees: a mesh whose default surface turns less everywhere has no correction at all and
no lattice is made where no cage star spreads above ``rule.turn_spread`` (bit for bit the
surface without this step: every sphere, torus and height field of bench_shape, Blender's
primitives, the airplane and the bone).

The correction is a fixed linear function of the positions, zero for constants (it reads
differences X_u - X_v), local (rings 1-2 of v) and affine covariant, so the surface stays a
fixed sparse linear function of X for a fixed topology and rest shape: :class:`FairedFits`
adds it to the coupled fits. Interpolation, the partition of unity and smoothness are
untouched: only coefficients of degree >= 1 change, S = X_v at every vertex.

Cost: the rest surface is evaluated only on the lattice points it is read at (the pairs
having a triangle in a looked-at face, then the regions' pairs), the partition and
monomials of that evaluation give the factor's columns, and a region's penalty recomputes
only the triangles its unknowns move (:class:`_Penalty`); the values are bit for bit those
of evaluating everything.

Exact: the correction is applied exactly as a linear map. Approximate: the weights are
where L-BFGS stops (``rule.turn_iterations`` iterations, or an iteration gaining less than
1e-7) in a non-convex problem: deterministic for the same inputs and arithmetic, but
round-off of the rest shape can move the surface (perturbations of 1e-15 relative:
Suzanne by 5e-10, the cow by 1e-6, bunny10k by 2e-5, of models 2.7, 1.8 and 15.6 wide;
the fold counts at r = 4, 8 and 16 unchanged; docs/design.md, "Fairing").
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp
from scipy.optimize import minimize
from scipy.sparse.csgraph import connected_components

from .coupling import zero_row_sums
from .evaluate import _blend
from .fillets import face_geometry
from .memory import BUILD_MIN_BUDGET, fairing_estimate
from .monomials import monomial_exponents
from .polygon_map import map_points
from .triangle_edges import triangle_pairs

__all__ = ["TurnCorrection", "FairedFits", "FairingSkipped", "turn_correction"]

# a star's ring-1 offsets are (nearly) flat where their second moment's smallest
# eigenvalue is at most FLAT times the largest: rings 1-2 carry its corrections. Not the
# pseudo-inverse's cut-off (RCOND): the least-norm weights grow as 1 / sqrt(eigenvalue),
# and measured on a box with support loops whose inset corners were lifted by eps, with
# FLAT = RCOND the weights reached 56 at eps = 3e-4 and a drag of one corner by 0.05 threw
# the surface over 4.2 (the box 0.5 thick); at 1e-2 they stay within 0.4-0.7 and 0.61
FLAT = 1e-2
RCOND = 1e-8
# L-BFGS runs again (at most RESTARTS times, from where it stopped) on a region that still
# has a pair beyond 90 degrees: measured, an exact, mirror-symmetric L slab with support
# loops stopped at 30 iterations with 26 / 2 of its pairs beyond 60 / 90 degrees (the
# output 26 / 2 / 103 at r = 8); with the restarts 0 / 0 / 37, as the same slab moved by
# 1e-6; Suzanne, the cow, bunny10k, Blender's primitives, the bevels and the extrusions
# bit-identical (no region of theirs folds after the first run)
RESTARTS = 2


class FairingSkipped(Exception):
    """The fairing's lattice would need more memory than the build may use (``points``:
    its size): the surface is built without the correction (and says so)."""

    def __init__(self, points: int):
        super().__init__(points)
        self.points = points


@dataclass(frozen=True)
class TurnCorrection:
    """delta c (V MMAX, k) = sum over terms t of weight_t (X[neighbour_t] - X[vertex_t]) in
    row row_t (v MMAX + m): a linear map of the positions X (V, k), zero for constants."""

    row: np.ndarray        # (K,) int64
    vertex: np.ndarray     # (K,) int64
    neighbour: np.ndarray  # (K,) int64
    weight: np.ndarray     # (K,) float64
    shape: tuple           # (V MMAX, V)

    def __call__(self, X) -> np.ndarray:
        X = np.asarray(X, dtype=np.float64)
        d = X[self.neighbour] - X[self.vertex]
        if X.ndim == 1:
            return np.bincount(self.row, self.weight * d, minlength=self.shape[0])
        return np.stack([np.bincount(self.row, self.weight * d[:, j], minlength=self.shape[0])
                         for j in range(d.shape[1])], axis=1)

    @cached_property
    def operator(self) -> sp.csr_matrix:
        """(V MMAX, V) csr: weight at the neighbour's column, -weight at the vertex's; every
        row sums to 0 exactly (the vertex's entry is minus the sum of the row's others)."""
        return zero_row_sums(sp.csr_matrix((self.weight, (self.row, self.neighbour)),
                                           shape=self.shape))

    @cached_property
    def _csc(self) -> sp.csc_matrix:
        return self.operator.tocsc()

    def columns(self, cols) -> sp.csc_matrix:
        """Columns ``cols`` (m,) of :attr:`operator` (csc (V MMAX, m))."""
        return self._csc[:, np.asarray(cols, dtype=np.int64).ravel()]


class FairedFits:
    """The coupled fits (:class:`gerbs_core.mesh.coupling.CoupledFits`) plus a
    :class:`TurnCorrection`: ``fits(X) = inner(X) + correction(X)``; the same interface
    (``operator``, ``columns``, ``operator_built``, ``shape``). Immutable."""

    def __init__(self, inner, correction: TurnCorrection):
        self.inner, self.correction = inner, correction
        self.shape = inner.shape

    def __call__(self, X):
        return self.inner(X) + self.correction(X)

    @cached_property
    def operator(self) -> sp.csr_matrix:
        """(V MMAX, V) csr, rows summing to 0 exactly (as :attr:`CoupledFits.operator`)."""
        return zero_row_sums(self.inner.operator + self.correction.operator)

    @property
    def operator_built(self) -> bool:
        return "operator" in self.__dict__

    def columns(self, cols) -> sp.csc_matrix:
        """Columns ``cols`` (m,) of :attr:`operator` (csc), without making it if it is not
        made: the inner map's columns (on a neighbourhood) plus the correction's."""
        if self.operator_built:
            return self._csc[:, np.asarray(cols, dtype=np.int64).ravel()]
        return (self.inner.columns(cols) + self.correction.columns(cols)).tocsc()

    @cached_property
    def _csc(self) -> sp.csc_matrix:
        return self.operator.tocsc()


def _cross(a, b):
    """Cross products of the columns of (3, n) arrays (rows x, y, z)."""
    out = np.empty((3, a.shape[1]))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        np.multiply(a[j], b[k], out=out[i])
        out[i] -= a[k] * b[j]
    return out


def _dots(a, b):
    """Dot products (n,) of the columns of (3, n) arrays, summed as (x + z) + y (the order
    of numpy's einsum over three, which the first implementation used)."""
    return (a[0] * b[0] + a[2] * b[2]) + a[1] * b[1]


def _normals(x, t):
    """(unit normals (3, m), (e1, e2) (3, m) the edges from corner 0, |e1 x e2| (m,)) of the
    triangles t (3, m) (their corners' indices, one row per corner) of points x (3, N)."""
    x0, x1, x2 = np.take(x, t, axis=1).transpose(1, 0, 2)      # (3, m) each
    e1, e2 = x1 - x0, x2 - x0
    c = _cross(e1, e2)
    ln = np.sqrt(_dots(c, c))
    c /= np.maximum(ln, 1e-300)
    return c, (e1, e2), ln


def turn_penalty(P, T, A, B, cos0):
    """(sum over pairs of max(0, cos0 - n_A . n_B)^2, its gradient w.r.t. P (N, 3)) for
    triangles T (n, 3) of points P (N, 3) and the pairs (A, B) of adjacent triangles: the
    penalty the fairing minimises (:class:`_Penalty` with the points as the unknowns)."""
    P = np.asarray(P, dtype=np.float64)
    pen = _Penalty(P, sp.identity(len(P), format="csr"), np.asarray(T), np.asarray(A),
                   np.asarray(B), cos0)
    return pen(np.zeros_like(P))


def ring1_pairs(topo) -> tuple[np.ndarray, np.ndarray]:
    """(v, u) (K,) each: the directed pairs of distinct corners of a common face, once
    each, sorted by v then u."""
    sizes = np.asarray(topo.face_sizes, dtype=np.int64)
    fo, fv = np.asarray(topo.face_offsets), np.asarray(topo.face_vertices)
    corner = np.repeat(np.arange(len(fv)), np.repeat(sizes, sizes))      # corner c, n times
    first = np.repeat(fo[:-1], sizes * sizes)
    k = np.arange(len(corner)) - np.repeat(np.cumsum(sizes * sizes) - sizes * sizes, sizes * sizes)
    other = first + k % np.repeat(sizes, sizes * sizes)
    v, u = fv[corner], fv[other]
    keep = v != u
    n = int(topo.n_vertices)
    key = np.unique(v[keep] * n + u[keep])
    return key // n, key % n


def _face_terms(model, face_ids, x, need=None):
    """Per chunk of same-size faces of the points (face_ids (N,), layout coordinates x (N, 2);
    :func:`gerbs_core.mesh.evaluate.groups`): (sel (F, P) the points' indices or -1, u (n, F)
    the corners, Psi (n, F, P) the partition, mono (n, F, P, M) the corners' monomials up to
    their highest degree), from :func:`gerbs_core.mesh.evaluate.corner_terms`. ``need`` (V,)
    bool: only the chunks having such a corner (None: all)."""
    from .evaluate import corner_terms, groups

    topo = model.topology
    for n, faces, sel, xb in groups(topo, model.layouts.corners, face_ids, x):
        u = topo.face_vertices[topo.face_offsets[faces][None, :] + np.arange(n)[:, None]]
        if need is not None and not need[u].any():
            continue
        _, Psi, mono, _ = corner_terms(model, n, faces, xb, 0, int(model.degrees[u].max()))
        yield sel, u, Psi[0], mono[0]


def _rest_points(model, X, coef, face_ids, x, P0, at):
    """The surface of positions X (V, 3) and coefficients coef (V, MMAX, 3) (``model.fits(X)``)
    at the face points ``at`` of (face_ids (N,), layout coordinates x (N, 2)), written into
    P0[at] (P0 (N, 3)): bit for bit :func:`gerbs_core.mesh.evaluate.evaluate` (the same
    operations per face; a point's value does not depend on the others evaluated with it).
    Returns the :func:`_face_terms` it used (their indices into the N points), for
    :func:`point_factors`."""
    terms = []
    # faces by their number of such points (within a factor 2), so that a face with a few
    # of them (a strip along a side) is not padded to a whole face's count
    count = np.bincount(face_ids[at], minlength=model.topology.n_faces)[face_ids[at]]
    size = np.ceil(np.log2(count)).astype(np.int64)
    for b in np.unique(size):
        ab = at[size == b]
        for sel, u, Psi, mono in _face_terms(model, face_ids[ab], x[ab]):
            ok = sel >= 0
            sel = np.where(ok, ab[np.maximum(sel, 0)], -1)
            P0[sel[ok]] = _blend([Psi], [mono], X[u], coef[u][:, :, :mono.shape[-1]], 0)[0][ok]
            terms.append((sel, u, Psi, mono))
    return terms


def point_factors(model, face_ids, x, rows, terms=None):
    """E csr (N, len(rows)): the columns ``rows`` (v MMAX + m, sorted) of the stencil's
    factor E (:mod:`gerbs_core.mesh.stencil`) at face points (face_ids (N,), layout
    coordinates x (N, 2)): S = B X + E c, so E[:, rows] maps those coefficients to the
    points. Only the terms of those rows are made; ``terms``: :func:`_face_terms` if
    already made (:func:`_rest_points`' return); then E has entries only in the rows of
    the points those terms cover (the others' rows are empty: points no pair reads)."""
    topo = model.topology
    V, mmax = topo.n_vertices, len(monomial_exponents(4))
    col = np.full(V * mmax, -1, dtype=np.int64)
    col[rows] = np.arange(len(rows))
    mine = np.zeros(V, bool)
    mine[np.asarray(rows) // mmax] = True
    r_, c_, v_ = [], [], []
    for sel, u, Psi, mono in (_face_terms(model, face_ids, x, mine) if terms is None else terms):
        if not mine[u].any():
            continue
        M = mono.shape[-1]
        cols = col[u[..., None] * mmax + np.arange(M)]                 # (n, F, M)
        k, f, m = np.nonzero(cols >= 0)
        val = Psi[k, f] * mono[k, f, :, m]                              # (t, P)
        ok = sel[f] >= 0                                                # (t, P)
        r_.append(sel[f][ok])
        c_.append(np.broadcast_to(cols[k, f, m][:, None], ok.shape)[ok])
        v_.append(val[ok])
    def cat(parts, dtype):
        out = np.concatenate(parts) if parts else np.empty(0, dtype)
        parts.clear()
        return out

    return sp.csr_matrix((cat(v_, float), (cat(r_, np.int64), cat(c_, np.int64))),
                         shape=(len(face_ids), len(rows)))


def turn_correction(model, X, rings_h, ring1, rule, star, budget: float = 2.0e9):
    """(the :class:`TurnCorrection` of a model's fits on the rest positions X (V, 3), or None
    where the surface nowhere turns more than ``rule.turn`` degrees between neighbouring
    triangles of the lattice at ``rule.turn_resolution`` (module docstring); the number of
    lattice points looked at). FairingSkipped where they would need more memory than the
    larger of ``budget`` and the build's minimum (:func:`gerbs_core.mesh.memory.fairing_estimate`).

    rings_h (V,) the stars' scales; ring1 (v, u) the directed ring-1 pairs
    (:func:`ring1_pairs`); star (V,) the cage stars' spreads in degrees
    (:func:`gerbs_core.mesh.spread_fits.star_spread`): only the faces having a corner whose
    star spreads above ``rule.turn_spread`` are looked at (a smooth fine mesh: none, and no
    lattice is made)."""
    from .lattice import Lattice
    from .lattice_templates import obtuse_flips

    if rule.turn >= 180.0:
        return None, 0
    topo = model.topology
    V = topo.n_vertices
    expo = monomial_exponents(4)
    mmax = len(expo)
    mdeg = expo.sum(1)
    fo, fv, cf = topo.face_offsets, topo.face_vertices, topo.corner_face
    cand = np.zeros(topo.n_faces, bool)
    cand[cf[(np.asarray(star) > rule.turn_spread)[fv]]] = True
    if not cand.any():
        return None, 0
    v1, u1 = ring1
    # the faces where a correction can move points: those of the vertices within ring 1
    # of a candidate face's corners (a superset of the active vertices' faces, below)
    near = np.zeros(V, bool)
    near[fv[cand[cf]]] = True
    near[u1[near[v1]]] = True
    sel = np.zeros(topo.n_faces, bool)
    sel[cf[near[fv]]] = True
    # the output's own triangulation at that resolution (obtuse faces flipped)
    lat = Lattice(topo, rule.turn_resolution, flip=obtuse_flips(topo, model.layouts.angles))
    tface = np.asarray(lat.triangle_face)
    tsel = np.flatnonzero(sel[tface])
    Tall = np.asarray(lat.triangles)[tsel]
    pts, T = _compact(Tall.ravel(), lat.n_points)
    if fairing_estimate(len(pts)) > max(float(budget), BUILD_MIN_BUDGET):
        raise FairingSkipped(len(pts))
    T = T.reshape(-1, 3)
    tface = tface[tsel]
    uv, fan = lat.sample_params()
    face = np.asarray(lat.face)[pts]
    x = map_points(topo, np.asarray(model.layouts.corners, dtype=np.float64), face, fan[pts],
                   uv[pts])
    A, B = triangle_pairs(T)
    cos0 = np.cos(np.radians(rule.turn))
    # the rest surface (NaN where not needed): first on the pairs having a triangle in a
    # candidate face, the only ones whose turn can make unknowns
    P0 = np.full((len(pts), 3), np.nan)
    look = np.flatnonzero(cand[tface[A]] | cand[tface[B]])
    tl, ab = _compact(np.concatenate([A[look], B[look]]), len(T))
    done = np.zeros(len(pts), bool)
    done[T[tl]] = True
    coef = model.fits(X).reshape(V, mmax, -1)
    terms = _rest_points(model, X, coef, face, x, P0, np.flatnonzero(done))
    n0 = _normals(np.ascontiguousarray(P0.T), np.ascontiguousarray(T[tl].T))[0]
    hot = look[_dots(np.take(n0, ab[:len(look)], axis=1),
                     np.take(n0, ab[len(look):], axis=1)) < cos0]
    if not len(hot):
        return None, len(pts)
    # the variables: the corners of the faces holding a turn above the bound, and ring 1
    faces = np.unique(tface[np.concatenate([A[hot], B[hot]])])
    corners = np.unique(np.concatenate([fv[fo[f]:fo[f + 1]] for f in faces]))
    act = np.zeros(V, bool)
    act[corners] = True
    act[u1[act[v1]]] = True
    deg = np.asarray(model.degrees)
    # the unknowns: delta c of the rows (v, m), v active, m of degree <= min(deg v,
    # turn_degree), scaled to z = h_v^(|m|-1) delta c (dimensionless)
    nm = np.searchsorted(np.sort(mdeg), np.minimum(deg, rule.turn_degree), side="right")
    order = np.argsort(mdeg, kind="stable")
    av = np.flatnonzero(act)
    rv = np.repeat(av, nm[av])
    rm = order[np.arange(len(rv)) - np.repeat(np.cumsum(nm[av]) - nm[av], nm[av])]
    rows = rv * mmax + rm
    scale = rings_h[rv] ** (mdeg[rm] - 1.0)
    # the regions of sharp turns (connected components of the active vertices in ring 1),
    # faired one after the other, each on the points its rows move, and kept only where it
    # turns its pairs less than before (a region where the optimisation does not settle,
    # e.g. among slivers, stays as it was)
    graph = sp.csr_matrix((np.ones(len(v1)), (v1, u1)), shape=(V, V))[av][:, av]
    region = np.full(V, -1)
    region[av] = connected_components(graph, directed=False)[1]
    row_region = region[rv]
    # the points the rows move: those of the faces having an active corner, labelled with
    # the corner's region (a face's corners are in one another's ring 1, so in one region);
    # every pair having a point a region moves is in its penalty
    fregion = np.full(topo.n_faces, -1)
    fregion[cf[act[fv]]] = region[fv[act[fv]]]
    label = fregion[face]
    G = int(region.max()) + 1
    pairs, bounds = _region_pairs(label[T], A, B, G)
    # the rest surface on the rest of those pairs' points
    more = np.zeros(len(pts), bool)
    more[T[A[pairs]]] = True
    more[T[B[pairs]]] = True
    terms += _rest_points(model, X, coef, face, x, P0, np.flatnonzero(more & ~done))
    # every point a penalty reads is evaluated now (the rest stay NaN); where the surface
    # itself is not finite (a cover with holes) a NaN cosine would drop its pair silently:
    # nothing to fair by, and the surface's own checks report it
    if not np.isfinite(P0[more | done]).all():
        return None, len(pts)
    # the factor's columns of the rows on the points they move, scaled to the unknowns z
    Es = point_factors(model, face, x, rows, terms)
    del terms
    Es.data /= scale[Es.indices]
    Ec = Es.tocsc()
    # the stay's weight per lattice point: turn_stay / (the area of its rest face), so that
    # the term is dimensionless and every face weighs the same, whatever its size
    stay = rule.turn_stay / np.maximum(face_geometry(topo, X)[2], 1e-300)[face] \
        if rule.turn_stay else None
    P = P0.copy()
    z = np.zeros((len(rows), 3))
    for g in range(G):
        cols = np.flatnonzero(row_region == g)
        E = Ec[:, cols].tocsr()
        check = pairs[bounds[g]:bounds[g + 1]]
        zg = _fair_region(P, E, T, A[check], B[check], cos0, rule, stay)
        if zg is not None:
            P += E @ zg
            z[cols] = zg
    dc = z / scale[:, None]
    # delta c of row (v, m) as the least-norm combination of v's offsets X_u - X_v over ring
    # 1, and over rings 1-2 where ring 1 is flat (no normal component otherwise): exact
    # where they span R^3, else its projection on their span
    pv, pu = _offset_pairs(v1, u1, act, X)
    first = np.searchsorted(pv, rv)                   # pv is sorted: v's pairs start here
    count = np.bincount(pv, minlength=V)[rv]
    rep = np.repeat(np.arange(len(rows)), count)
    k = first[rep] + np.arange(len(rep)) - np.repeat(np.cumsum(count) - count, count)
    tv, tu = pv[k], pu[k]
    D = X[tu] - X[tv]
    a = _offset_weights(dc[rep], D, tv, pv, X[pu] - X[pv], V)
    keep = a != 0.0
    return TurnCorrection(rows[rep][keep], tv[keep], tu[keep], a[keep], (V * mmax, V)), len(pts)


def _compact(ids, n):
    """(the distinct values u of ids (k,) in [0, n), ascending; ids' ranks in u): np.unique
    with return_inverse, by marks instead of a sort."""
    mark = np.zeros(n, bool)
    mark[ids] = True
    u = np.flatnonzero(mark)
    rank = np.empty(n, np.int64)
    rank[u] = np.arange(len(u))
    return u, rank[ids]


def _region_pairs(labels, A, B, G):
    """(pairs, bounds): the pairs (A, B) of triangles having a point of region g (labels
    (t, 3) the regions of the triangles' points, -1 none) are pairs[bounds[g]:bounds[g+1]],
    ascending."""
    thi = labels.max(axis=1)                                    # per triangle
    tlo = np.where(labels >= 0, labels, G).min(axis=1)
    hi = np.maximum(thi[A], thi[B])
    lo = np.minimum(tlo[A], tlo[B])
    one = np.flatnonzero((hi >= 0) & (lo == hi))                # a single region (nearly all)
    many = np.flatnonzero((hi >= 0) & (lo < hi))
    sub = np.concatenate([labels[A[many]], labels[B[many]]], axis=1).ravel()
    at = np.repeat(many, 6)[sub >= 0]
    n = len(A)
    key = np.concatenate([hi[one] * n + one, np.unique(sub[sub >= 0] * n + at)])
    key.sort()
    return key % n, np.searchsorted(key // n, np.arange(G + 1))


def _fair_region(P, E, T, A, B, cos0, rule, stay=None):
    """The scaled corrections z (n, 3) of one region (module docstring) or None: E (N, n)
    the region's columns of the scaled factor on the lattice points, P (N, 3) the points
    now; (A, B) every pair of triangles T having a point E moves; stay (N,) the stay's
    weight per point or None."""
    # every pair the region can change is in the penalty: measured, leaving out those far
    # below the bound (20 degrees) let the optimisation fold them (the cow: 84 / 42 pairs
    # above 60 / 90 degrees against 10 / 0) and made its outcome depend on round-off
    pen = _Penalty(P, E, T, A, B, cos0, stay)
    zero = np.zeros((E.shape[1], 3))
    cos = pen.cosines(zero)
    if not (cos < cos0).any():
        return None
    weight = rule.turn_weight

    def f(z):
        F, g = pen(z.reshape(-1, 3))
        return F + weight * float(np.dot(z, z)), (g + 2.0 * weight * z.reshape(-1, 3)).ravel()

    # ftol: L-BFGS-B stops when an iteration lowers f by less than ftol max(|f|, 1), i.e.
    # (f < 1) by less than a tenth of the squared excess of one pair 0.1 degrees beyond the
    # bound. Measured against 1e-9: the same fold counts at r = 4 / 8 / 16 on Suzanne, the
    # cow and bunny10k, unperturbed and perturbed (the cow's r = 4 pairs above 90: 9 -> 8),
    # in 26% / 32% fewer evaluations on the cow / bunny10k (where regions settle early and
    # the line searches then wasted evaluations at round-off level)
    z = zero.ravel()
    for _ in range(1 + RESTARTS):
        z = minimize(f, z, jac=True, method="L-BFGS-B",
                     options={"maxiter": rule.turn_iterations, "maxcor": 10,
                              "ftol": 1e-7, "gtol": 1e-7}).x
        # a region that still folds (a pair beyond 90 degrees) starts again from where it
        # stopped, with a fresh curvature memory
        if not (pen.cosines(z.reshape(-1, 3)) < 0.0).any():
            break
    z = z.reshape(-1, 3)
    now = pen.cosines(z)
    # kept where it turns the region's pairs less: a smaller sum of squared excesses over
    # the bound and no more pairs beyond 60 or 90 degrees
    ex0, ex1 = np.maximum(0.0, cos0 - cos), np.maximum(0.0, cos0 - now)
    worse = any(int((now < t).sum()) > int((cos < t).sum()) for t in (0.5, 0.0))
    return None if worse or np.dot(ex1, ex1) >= np.dot(ex0, ex0) else z


class _Penalty:
    """The turn penalty sum over the pairs (A, B) of lattice triangles T (t, 3) of
    max(0, cos0 - n_A . n_B)^2, plus sum_p stay_p |(Es z)_p|^2 with ``stay`` (N,) >= 0 (None:
    no such term), as a function of the unknowns z (n, 3): points P0 (N, 3) + Es (N, n) z.
    Only the triangles having a point that Es moves (a stored entry in its row) are
    recomputed per call (the first m of the pairs' triangles, in this order); the others
    keep their normals at z = 0. Coordinates are rows ((3, k) arrays)."""

    def __init__(self, P0, Es, T, A, B, cos0, stay=None):
        tris, inv = _compact(np.concatenate([A, B]), len(T))
        pts, Tl = _compact(T[tris].ravel(), len(P0))
        Tl = Tl.reshape(-1, 3)                              # (t, 3) into pts
        E = Es[pts]
        mov = (np.diff(E.indptr) > 0)[Tl].any(axis=1)
        order = np.concatenate([np.flatnonzero(mov), np.flatnonzero(~mov)])
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        self.A, self.B = rank[inv[:len(A)]], rank[inv[len(A):]]
        self.m = m = int(mov.sum())
        mp, tm = _compact(Tl[mov].ravel(), len(pts))        # the moving triangles' points
        self.t = np.ascontiguousarray(tm.reshape(-1, 3).T)  # (3, m) into mp
        self.x0 = np.ascontiguousarray(P0[pts][mp].T)       # (3, len(mp))
        self.E = E[mp]
        # the normals (3, t): the moving triangles' rewritten per call, the others' fixed
        self.N = np.empty((3, len(tris)))
        self.N[:, m:] = _normals(np.ascontiguousarray(P0[pts].T),
                                 np.ascontiguousarray(Tl[~mov].T))[0]
        self.cos0 = cos0
        self.stay = None if stay is None else np.asarray(stay)[pts][mp]

    def _update(self, z):
        """The moving triangles' (normals, (e1, e2), |e1 x e2|) at z, written into N too."""
        zt = np.ascontiguousarray(np.asarray(z).T)
        x = np.empty_like(self.x0)
        for j in range(3):
            np.add(self.x0[j], self.E @ zt[j], out=x[j])
        self.x = x
        out = _normals(x, self.t)
        self.N[:, :self.m] = out[0]
        return out

    def cosines(self, z):
        """n_A . n_B (pairs,) at z."""
        self._update(z)
        return _dots(np.take(self.N, self.A, axis=1), np.take(self.N, self.B, axis=1))

    def __call__(self, z):
        """(the penalty, its gradient (n, 3) w.r.t. z): the turn's gradient over the pairs
        beyond the bound only (the others add nothing), the stay's 2 Es^T (stay (Es z))."""
        n, (e1, e2), ln = self._update(z)
        N, A, B = self.N, self.A, self.B
        nA, nB = np.take(N, A, axis=1), np.take(N, B, axis=1)
        c = _dots(nA, nB)
        on = np.flatnonzero(c < self.cos0)
        F0, g0 = 0.0, np.zeros((self.E.shape[1], 3))
        if self.stay is not None:
            d = self.x - self.x0
            F0 = float(np.dot(self.stay, (d * d).sum(0)))
            g0 = self.E.T @ (2.0 * self.stay * d).T
        if not len(on):
            return F0, g0
        r = self.cos0 - c[on]
        # dF/dn per triangle: -2 r n_B at A, -2 r n_A at B (summed in pair order)
        ab = np.concatenate([A[on], B[on]])
        w = np.concatenate([-2.0 * r * nB[:, on], -2.0 * r * nA[:, on]], axis=1)
        hit = np.zeros(N.shape[1], bool)
        hit[ab] = True
        k = np.flatnonzero(hit[:self.m])                    # moving triangles touched
        gn = np.stack([np.bincount(ab, w[j], minlength=N.shape[1])[k] for j in range(3)])
        nk = np.take(n, k, axis=1)
        # through n = c / |c|: dF/dc = (gn - (gn . n) n) / |c|
        gc = (gn - _dots(gn, nk) * nk) / np.maximum(ln[k], 1e-300)
        g1 = _cross(np.take(e2, k, axis=1), gc)   # c = e1 x e2, e_i = p_i - p0
        g2 = _cross(gc, np.take(e1, k, axis=1))
        # dF/dp per point (corner 0's terms, then corner 1's, 2's), then E^T over them
        tk = np.take(self.t, k, axis=1).ravel()
        g = np.concatenate([-(g1 + g2), g1, g2], axis=1)
        hit = np.zeros(len(self.x0[0]), bool)
        hit[tk] = True
        p = np.flatnonzero(hit)
        G = np.stack([np.bincount(tk, g[j], minlength=len(hit))[p] for j in range(3)], axis=1)
        # E[p]^T G without making E[p]: the entries of rows p, in order (so every sum runs
        # over the points in ascending order, as a product with E[p]^T would)
        E = self.E
        lo, cnt = E.indptr[p], E.indptr[p + 1] - E.indptr[p]
        at = np.arange(cnt.sum()) + np.repeat(lo - (np.cumsum(cnt) - cnt), cnt)
        cols, vals = E.indices[at], E.data[at]
        n = E.shape[1]
        grad = np.stack([np.bincount(cols, vals * np.repeat(G[:, j], cnt), minlength=n)
                         for j in range(3)], axis=1)
        return float(np.dot(r, r)) + F0, grad + g0


def _second_moments(pv, offsets, V) -> np.ndarray:
    """(V, 3, 3): sum of d d^T over the offsets d (K, 3) of each vertex pv (K,)."""
    M = np.zeros((V, 3, 3))
    for i in range(3):
        for j in range(3):
            M[:, i, j] = np.bincount(pv, offsets[:, i] * offsets[:, j], minlength=V)
    return M


def _offset_pairs(v1, u1, act, X) -> tuple[np.ndarray, np.ndarray]:
    """(pv, pu) (K,) each, sorted by pv then pu: the offsets X_u - X_v a correction of the
    active vertices (``act`` (V,) bool) is written in. Ring 1 (the directed pairs (v1, u1)),
    and rings 1-2 at a vertex whose ring-1 offsets are (nearly) flat (the smallest eigenvalue
    of their second moment below FLAT times the largest): a flat star's offsets cannot carry
    a correction across its plane (measured: an extruded L slab with support loops kept 11
    output pairs above 90 degrees, the fairing's own count 2, with 53 of 268 corrections
    losing more than a tenth of their length), a nearly flat one only with large weights."""
    V = len(act)
    pv, pu = v1[act[v1]], u1[act[v1]]
    lam = np.linalg.eigvalsh(_second_moments(pv, X[pu] - X[pv], V))
    flat = act & (lam[:, 0] <= FLAT * lam[:, 2])
    if not flat.any():
        return pv, pu
    R = sp.csr_matrix((np.ones(len(v1)), (v1, u1)), shape=(V, V))
    two = (R[np.flatnonzero(flat)] @ R).tocoo()
    wv, wu = np.flatnonzero(flat)[two.row], two.col
    key = np.unique(np.concatenate([pv * V + pu, (wv * V + wu)[wv != wu]]))
    return key // V, key % V


def _offset_weights(target, D, owner, pair_vertex, pair_offset, V):
    """a (K,) with sum over the terms k of a row of a_k D_k equal to the row's target
    (``target`` (K, 3) the target of each term's row), of least norm: a_k = D_k . M_v^+
    target_k with M_v = sum of d d^T over v's offsets d (``pair_vertex``, ``pair_offset``:
    each (v, u) once, :func:`_offset_pairs`); ``owner`` (K,) the terms' vertices."""
    Mp = np.linalg.pinv(_second_moments(pair_vertex, pair_offset, V), rcond=RCOND, hermitian=True)
    return np.einsum("ki,kij,kj->k", D, Mp[owner], target)



