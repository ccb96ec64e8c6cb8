"""Local functions that agree: the choice and the coupling of the fits (the fair-shape rule).

S = sum_v Psi_v l_v, so where supports overlap the second derivatives of S carry
Psi_v'' (l_v - l_w): what makes a blending surface fair is not the curvature of
each l_v but the disagreement of neighbouring local functions where they are
blended. On the rest shape (so that the surface stays a fixed sparse linear
function of the positions), with the agreement energy on sample points p of
every face

    A(l) = sum_p sum_k Psi_k (1 - Psi_k) |l_k(p) - T_k(p)|^2 = sum_p sum_{k<j} Psi_k Psi_j |l_k - l_j|^2
           (T_k the Psi-weighted mean of the face's other local functions),

and the tension energy sum_p s_f Psi_k |l_k(p) - C(p)|^2 (C the piecewise-linear
cage point, s_f the face's sharpness in [0, 1]: 0 below ``SHARP_FROM`` degrees
between the normals of adjacent rest faces, 1 above ``SHARP_TO``, plus ``rule.fillet`` times
its weight as the wide side of a bevelled edge, :mod:`gerbs_core.mesh.fillets`) -- which
keeps the surface near the cage where the cage has sharp or bevelled edges (the Cube,
the Cylinder's rims, a bevelled box) and vanishes on smooth meshes, whose convergence it
would spoil:

1. *choice*: every vertex takes the candidate data fit (degree 2..4, one or two
   rings, :data:`gerbs_core.mesh.fits.CANDIDATES`) of least MU * A + LAMBDA * tension
   + FOLD * fold penalty given its neighbours' choices (``CHOICE_ROUNDS`` simultaneous
   rounds, ties to the lower degree): degree 4 where a mesh is fine and regular, 2
   where it is coarse. The fold penalty sum_p h_v^2 w Psi_v max(0, FOLD_COS - n_l . n_f)^2
   (n_l the candidate's unit normal at p, n_f the rest normal of p's face) charges a
   candidate that turns by more than arccos(FOLD_COS) against the face it is blended
   over -- a fold of the local function itself, which the agreement cannot see where
   one Psi dominates. It is zero on smooth meshes and depends on the rest shape only;
2. *coupling* (:mod:`gerbs_core.mesh.coupling`): ``SWEEPS`` damped block-Jacobi sweeps
   of data + MU * A + LAMBDA * tension, pinned (l_v(0) = X_v), starting from the chosen fits. Every sweep is a
   linear map of the previous coefficients, so the result is linear in the positions
   and local: a coefficient of v depends on the vertices within (data rings +
   SWEEPS) rings of v.

Measured (bench_shape, docs/design.md): against the plain degree-2 fits, Suzanne's
adjacent output pairs above 60 / 90 degrees drop from 142 / 48 to 82 / 12 (the former
rule, without the fold penalty and with energies at lattice resolution 4: 90 / 26),
the icosphere's curvature error 3-5x and the torus's 8x,
with the Cube and Cylinder inside the acceptance boxes.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..gauge.jet import partition_jet
from .cover import require_cover
from .coupling import coupled_fits, identity_fits
from .fits import CANDIDATES, candidate_fits_all, chosen_rows
from .monomials import monomial_exponents, monomial_gradients, monomials, n_monomials
from .row_values import (candidate_coefs, candidate_values, chunks, copy_aliases, own_rows,
                         per_degree, row_sums, square_norms)
from .fillets import fillet_sides, smoothstep
from .spread_fits import SPREAD, gate, spread_candidates, spread_faces, star_spread
from .validation import face_vector_areas

__all__ = ["FairnessRule", "DMAX", "fair_fits", "face_normals", "face_sharpness",
           "tension_weights"]

DMAX = 4                      # the highest degree of a local function
MMAX = n_monomials(DMAX)      # coefficients per vertex in the padded layout


@dataclass(frozen=True)
class FairnessRule:
    """Constants of the rule (module docstring); the defaults are the measured choice.

    mu: weight of the agreement energy against the data (both per unit of their sums);
    lam: weight of the tension on fully sharp faces; sharp_from / sharp_to (degrees):
    the normal angle where faces start / end being sharp; fold: weight of the fold
    penalty of the choice (0: off), fold_cos: the cosine below which a candidate's normal
    counts as turned against its face's; sweeps; damping in (0, 1]; choice_rounds;
    resolution of the sample lattice of the energies; fillet: the extra tension (times lam)
    on the wide faces beside a bevelled edge (:mod:`gerbs_core.mesh.fillets`; 0: none).
    """

    mu: float = 300.0
    lam: float = 75.0
    sharp_from: float = 50.0
    sharp_to: float = 80.0
    fold: float = 1000.0
    fold_cos: float = 0.3
    sweeps: int = 2
    damping: float = 0.7
    choice_rounds: int = 3
    # 3, not 4: measured (bench_shape) cow pairs above 90 degrees 116 -> 89, Suzanne 16 -> 12,
    # tori 1.1-1.5x smaller curvature errors, the Cylinder's r16/r8 dihedral 0.71 -> 0.58;
    # Suzanne above 60 degrees 74 -> 82, the Cone's largest dihedral at r = 8 39 -> 56
    resolution: int = 3
    candidates: tuple = CANDIDATES
    # stars spreading above this many degrees get an extra candidate (mesh.spread_fits)
    spread: float = SPREAD
    # the agreement weight of the coupling's rows, spread_mu x mu, on faces having a
    # corner whose star spreads above spread_mu_from degrees (the folds' stars: Suzanne's ears and mouth,
    # the cow's hooves; above the Cylinder's rims and the Cone's apex, 63.4, and the
    # Cube's corners, 54.7, which stay at mu). Measured (bench_shape, r = 8): Suzanne
    # 80 / 6 / 117 -> 76 / 4 / 119, cow 140 / 55 / 178 -> 126 / 50 / 176, the Cone's
    # largest dihedral 34.2 -> 31.9 degrees, every other input identical; 1.5 x mu
    # everywhere grows the Cube to 1.48x (docs/design.md "Folds", sharp_mu)
    spread_mu: float = 1.5
    spread_mu_from: float = 70.0
    # the fairing (mesh.fairing): the largest angle (degrees) between neighbouring triangles
    # of the lattice at turn_resolution before the coefficients are corrected (180: off),
    # the correction's weight per coefficient (dimensionless), L-BFGS's iterations per
    # region (30: the fold counts at r = 8 of 40, fewer at r = 4 and 16 on Suzanne and the
    # cow, in 25% fewer evaluations; docs/design.md "Fairing"), the highest degree of a
    # corrected monomial
    turn: float = 35.0
    turn_resolution: int = 8
    turn_weight: float = 0.03
    turn_iterations: int = 30
    turn_degree: int = 4
    # only faces having a corner whose cage star spreads above this (degrees) are looked
    # at (smooth fine meshes: no lattice is made)
    turn_spread: float = 20.0
    # the fairing's stay: turn_stay times the squared distance each lattice point moves over
    # its rest face's area. Without it the cheapest way to turn less is to inflate a thin
    # part: measured (bench_shape --only proportions,extrusions, r = 8), Blender's Cube scaled
    # to a 4 x 0.5 x 0.2 plank 1.02 / 3.73 / 10.0 of the cage's box -> 1.04 / 1.77 / 3.32
    # at 0.03, a 2 x 2 x 0.2 board 1.23 / 1.23 / 3.05 -> 1.09 / 1.09 / 3.28, the L slab with
    # support loops 1.20 / 1.20 / 1.32 -> 1.14 / 1.13 / 1.17; Suzanne 0 / 0 / 37 -> 0 / 0 / 39
    # (zebra 167 / 700 -> 167 / 695), the cow 14 / 0 / 82 -> 14 / 0 / 83, bunny10k 6 / 0 / 74
    # -> 7 / 0 / 77. 0.1 takes the board to 2.70 in z but Suzanne at r = 4 from 46 to 70
    # pairs above 60 degrees (53 at 0.03); 0.3 lets the cow fold (20 / 1 / 111); every input
    # that is not faired is unchanged (docs/design.md "Fairing")
    turn_stay: float = 0.03
    # the tension on fillet sides (mesh.fillets: wide faces beside a bevelled edge) is
    # fillet x lam. Measured (bench_shape --only bevel, r = 8): Blender's Cube bevelled in
    # 1 / 2 / 4 segments 1.47 / 1.24 / 1.16 -> 1.09 / 1.05 / 1.03 of the cage's box at 10
    # (1.12 / 1.06 / 1.04 at 5, 1.07 / 1.03 / 1.02 at 20, where bunny10k gets a pair above
    # 90 degrees); every input of the default run without fillet sides is bit-identical
    fillet: float = 10.0

    def __post_init__(self):
        from ..errors import InvalidParameterError
        for name in ("mu", "lam", "fold", "spread_mu", "turn_weight", "turn_stay", "fillet"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise InvalidParameterError(name, f"must be finite and >= 0, got {v!r}")
        if not (np.isfinite(self.fold_cos) and -1 <= self.fold_cos <= 1):
            raise InvalidParameterError("fold_cos", f"must be in [-1, 1], got {self.fold_cos!r}")
        for name in ("spread", "spread_mu_from", "turn", "turn_spread"):
            v = getattr(self, name)
            if not (np.isfinite(v) and 0 <= v <= 180):
                raise InvalidParameterError(name, f"must be in [0, 180], got {v!r}")
        if not (0 <= self.sharp_from < self.sharp_to <= 180):
            raise InvalidParameterError("sharp_from", "need 0 <= sharp_from < sharp_to <= 180")
        if not (0 < self.damping <= 1):
            raise InvalidParameterError("damping", f"must be in (0, 1], got {self.damping!r}")
        for name in ("sweeps", "choice_rounds", "turn_iterations"):
            if int(getattr(self, name)) != getattr(self, name) or getattr(self, name) < 0:
                raise InvalidParameterError(name, "must be an integer >= 0")
        if int(self.turn_degree) != self.turn_degree or not 1 <= self.turn_degree <= DMAX:
            raise InvalidParameterError("turn_degree", f"must be an integer in [1, {DMAX}]")
        for name in ("resolution", "turn_resolution"):
            v = getattr(self, name)
            if int(v) != v or v < 2:
                raise InvalidParameterError(name, "must be an integer >= 2")


def face_normals(topo, X) -> np.ndarray:
    """Unit normals (F, 3) of the faces at positions X (V, 3): the normalised vector area
    (a non-planar face's mean orientation, :func:`~.validation.face_vector_areas`)."""
    fn = face_vector_areas(X, topo.face_sizes, topo.face_vertices)
    return fn / np.linalg.norm(fn, axis=1, keepdims=True)


def face_sharpness(topo, X, sharp_from: float, sharp_to: float) -> np.ndarray:
    """s_f (F,) in [0, 1]: smoothstep of the largest angle (degrees) between face f's normal
    and its edge neighbours' normals (rest shape), from sharp_from to sharp_to."""
    fn = face_normals(topo, X)
    ef = topo.edge_faces
    two = ef[:, 1] >= 0
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", fn[ef[two, 0]], fn[ef[two, 1]]),
                                       -1.0, 1.0)))
    worst = np.zeros(topo.n_faces)
    np.maximum.at(worst, ef[two, 0], ang)
    np.maximum.at(worst, ef[two, 1], ang)
    return smoothstep(worst, sharp_from, sharp_to)


def tension_weights(topo, X, rule: FairnessRule) -> np.ndarray:
    """s_f (F,) >= 0, the tension's weight per face (times ``rule.lam``): the sharpness
    (:func:`face_sharpness`, in [0, 1]) plus ``rule.fillet`` times the face's fillet side
    weight (:func:`gerbs_core.mesh.fillets.fillet_sides`, in [0, 1]; not computed at
    fillet = 0), on the rest positions X (V, 3)."""
    s = face_sharpness(topo, X, rule.sharp_from, rule.sharp_to)
    if rule.fillet:
        s = s + rule.fillet * fillet_sides(topo, X)
    return s


@dataclass(frozen=True)
class _Samples:
    """The energies' sample-corner pairs (SC rows): sample p, vertex v, Psi, sharpness s,
    unscaled monomials Bu (SC, MMAX), the scales' powers hpow (V, MMAX) = h_v^|m| (the
    scaled monomials Bs = Bu / h_v^|m| are made where needed: (SC, MMAX) float64 each,
    the largest arrays of the model's build); cage weights; the rows' chart positions
    y (SC, 2) and faces."""

    sample: np.ndarray
    vertex: np.ndarray
    y: np.ndarray
    face: np.ndarray
    psi: np.ndarray
    sharp: np.ndarray
    Bu: np.ndarray
    hpow: np.ndarray
    weight: np.ndarray   # quadrature weight (face area share / h_v^2)
    cage: sp.csr_matrix  # (L, V): the cage point of every sample
    n_samples: int

    @property
    def Bs(self) -> np.ndarray:
        """(SC, MMAX) the scaled monomials Bu / h_v^|m| (made on each use)."""
        return self.Bu / self.hpow[self.vertex]


def _shepard_weights(topo, corners2d, face, x, n):
    """(L, n) inverse-squared-distance (Shepard) weights of the corners of faces `face`
    (L,), all of n corners, at layout points x (L, 2): the tension's target, a point of the
    cage that tends to the vertex near a vertex. Measured against the piecewise-linear
    cage point (bilinear / fan): Blender's Cylinder 1.15x its cage instead of 1.32x (the
    PL target pulls the rim's local functions towards the vertical side, whose
    continuation then lifts the caps). Per face size: one (L, largest face) array made a
    100 x 100 grid with one 128-gon take 4 s here (a test with concave n-gons)."""
    cn = topo.face_offsets[face][:, None] + np.arange(n)
    d2 = square_norms(corners2d[cn] - x[:, None, :])
    big = functools.reduce(np.maximum, d2.T)                  # np.max(d2, axis=1), exact
    at = d2 <= 1e-24 * big[:, None]                           # a sample on a corner
    w = 1.0 / np.where(at, 1.0, d2)
    hit = at.any(axis=1)
    w[hit] = at[hit]
    return w / row_sums(w)[:, None]


def _shepard_cage(topo, corners2d, face, x):
    """csr (L, V): each layout point's Shepard combination of its face's vertices
    (:func:`_shepard_weights`)."""
    rows, cols, vals = [], [], []
    size = topo.face_sizes[face]
    for n in np.unique(size).tolist():
        sel = np.flatnonzero(size == n)
        w = _shepard_weights(topo, corners2d, face[sel], x[sel], n)
        rows.append(np.repeat(sel, n))
        cols.append(topo.face_vertices[topo.face_offsets[face[sel]][:, None] + np.arange(n)].ravel())
        vals.append(w.ravel())
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(len(face), topo.n_vertices))


def _samples(topo, charts, corners2d, cover, h, resolution, sharp_face):
    from .lattice import Lattice
    lat = Lattice(topo, resolution)
    x = lat.map_to_polygon(corners2d, local=True)
    lf = lat.local_face
    L = len(lf)
    counts = np.bincount(lf, minlength=topo.n_faces)
    cage = _shepard_cage(topo, corners2d, lf, x)
    parts = []
    for n in np.unique(topo.face_sizes).tolist():
        sel = np.flatnonzero(topo.face_sizes[lf] == n)
        c = topo.face_offsets[lf[sel]][None, :] + np.arange(n)[:, None]   # (n, Ln)
        Psi, y = np.empty(c.shape), np.empty(c.shape + (2,))
        eps = np.inf
        # in chunks of samples (cache-sized temporaries), written back in the rows' order
        for j in chunks(len(sel)):
            psi, pol = cover.psi_jet(charts, c[:, j], x[sel[j]][None], 0)
            eps = min(eps, float(psi[0].max(axis=0).min()))
            Psi[:, j] = partition_jet(psi, 0)[0]
            y[:, j] = charts.to_chart(c[:, j], x[sel[j]][None], pol=pol)[0]
        require_cover(eps, cover.kernel)
        v = topo.face_vertices[c]
        # rows with Psi = 0 (outside the vertex's support) or Psi = 1 (at the vertex: l_v = X_v
        # = the cage there) add exactly nothing to any energy: dropped (35-45% of the rows)
        live = (Psi > 0.0) & (Psi < 1.0)
        parts.append((np.broadcast_to(sel, c.shape)[live], v[live], Psi[live], y[live]))
    sample = np.concatenate([p[0] for p in parts])
    vertex = np.concatenate([p[1] for p in parts])
    psi = np.concatenate([p[2] for p in parts])
    y = np.concatenate([p[3] for p in parts])
    Bu = monomials(y, DMAX)[0]
    deg = monomial_exponents(DMAX).sum(1)
    hpow = h[:, None] ** deg[None, :]                       # the powers once per vertex
    face = lf[sample]
    # every face weighs the same, whatever its size (measured: weighting by area made
    # Suzanne's small faces count too little, 236 pairs above 60 degrees against 126)
    weight = 1.0 / counts[face]
    return _Samples(sample, vertex, y, face, psi, sharp_face[face], Bu, hpow, weight, cage, L)


def _fold_penalty(cands, X, smp, fn, h, rule, coefs=None):
    """(SC, ncand): fold h_v^2 w P max(0, fold_cos - cos(n_l(p), n_f))^2 per row and
    candidate, n_l the candidate's normal at the row's chart point, n_f its face's rest
    normal: it is zero unless the local function turns by more than arccos(fold_cos)
    against the face it is blended over (a fold of the local function itself)."""
    out = np.zeros((len(smp.vertex), len(cands)))
    if not rule.fold:
        return out
    coefs = candidate_coefs(cands, X) if coefs is None else coefs
    dmax = max(c.degree for c in cands)
    for sl in chunks(len(smp.vertex)):
        nf, vert = fn[smp.face[sl]], smp.vertex[sl]
        dm = monomial_gradients(smp.y[sl], dmax)                    # (2, SC, M)
        dm = dm.reshape(-1, dm.shape[-1])                           # (2 SC, M): d/dy1, d/dy2
        for i, own, d in per_degree(cands, coefs, dm, np.concatenate([vert, vert])):
            k = len(d) // 2                                          # own: both halves' rows
            n = np.cross(d[:k], d[k:])
            n /= np.maximum(np.sqrt(square_norms(n)), 1e-300)[:, None]    # np.linalg.norm's
            mine = slice(None) if own is None else own[:k]
            cos = np.einsum("ij,ij->i", n, nf[mine])
            out[sl, i][mine] = np.maximum(0.0, rule.fold_cos - cos) ** 2
        copy_aliases(out[sl], cands, vert)
    return (rule.fold * h[smp.vertex] ** 2 * smp.weight * smp.psi)[:, None] * out


# energies within this relative distance of a vertex's least count as ties (round-off:
# on symmetric meshes candidates tie exactly, and a change of summation order alone
# flipped 19 of a 32x32 grid's degrees)
TIE = 1e-9


def first_minimum(E: np.ndarray, tie: float = TIE) -> np.ndarray:
    """(V,) the first column of E (V, ncand) within ``tie`` (relative) of its row's least:
    the lower degree on ties, whatever the round-off of the energies' sums."""
    m = E.min(axis=1, keepdims=True)
    return np.argmax(E <= m + tie * np.abs(m), axis=1)


def _choose(cands, X, smp, rule, V, penalty, coefs=None):
    """The candidate of every vertex (V,): least agreement + lam * tension + the fold
    ``penalty`` (SC, ncand) (rest shape; mu weighs only the coupling, not the choice); coefs: the candidates' coefficients at X (made
    here if not given). An aliased candidate (:attr:`~gerbs_core.mesh.fits.CandidateFits.alias`)
    is evaluated on its own rows only; at the vertices it shares with its source j its
    energy is j's, as its evaluation would give it bit for bit (the same values), so the
    choice -- ties to the lower index -- is the same."""
    vals = candidate_values(cands, X, smp.vertex, smp.Bu, coefs)
    cage = (smp.cage @ X)[smp.sample]
    # per sample, not per face (unlike the coupling): measured Suzanne 126 pairs above
    # 60 degrees against 156 with the per-face weights
    P = smp.psi
    full = [i for i, c in enumerate(cands) if c.alias is None]
    part = [(i, *c.alias, own_rows(c, smp.vertex)) for i, c in enumerate(cands)
            if c.alias is not None]
    vf = vals if not part else vals[:, full]        # the candidates evaluated on every row
    tension = np.empty((len(P), len(full)))
    for sl in chunks(len(P)):               # row by row: cache-sized temporaries
        tension[sl] = (rule.lam * (smp.sharp[sl] * P[sl])[:, None]
                       * square_norms(vf[sl] - cage[sl, None]))
    tension += penalty[:, full]
    own_tension = [rule.lam * (smp.sharp[o] * P[o]) * square_norms(vals[o, i] - cage[o])
                   + penalty[o, i] for i, _, _, o in part]
    one = 1.0 - P
    # agreement of row s: P / (1 - P) |(1 - P) l - (T - P l_cur)|^2 (0 where P = 1)
    scale = np.where(one > 1e-12, P / np.where(one > 1e-12, one, 1.0), 0.0)
    choice = np.zeros(V, dtype=np.int64)
    energy = np.empty(tension.shape)
    E = np.empty((V, len(cands)))
    flat = vals.reshape(-1, 3)               # row s, candidate i at s * ncand + i
    base = np.arange(len(P)) * len(cands)
    for _ in range(rule.choice_rounds):
        cur = P[:, None] * flat[base + choice[smp.vertex]]
        S = np.stack([np.bincount(smp.sample, cur[:, k], minlength=smp.n_samples)
                      for k in range(3)], 1)
        others = S[smp.sample] - cur                           # sum of the other slots
        for sl in chunks(len(P)):
            gap = one[sl, None, None] * vf[sl] - others[sl, None, :]   # (1 - Psi) (l - T)
            energy[sl] = scale[sl, None] * square_norms(gap) + tension[sl]
        for k, i in enumerate(full):
            E[:, i] = np.bincount(smp.vertex, energy[:, k], minlength=V)
        for (i, j, same, o), t in zip(part, own_tension):
            gap = one[o, None] * vals[o, i] - others[o]
            mine = np.bincount(smp.vertex[o], scale[o] * square_norms(gap) + t, minlength=V)
            E[:, i] = np.where(same, E[:, j], mine)
        new = first_minimum(E)
        if np.array_equal(new, choice):
            break
        choice = new
    return choice


def _chosen(cands, choice, part, V):
    """The rows of each vertex's chosen candidate operator (``part``: "matrix" or "rhs"),
    in the padded (V*MMAX, V) layout (:func:`gerbs_core.mesh.fits.chosen_rows`)."""
    return chosen_rows(cands, choice, part, V, MMAX)


def fair_fits(topo, charts, corners2d, cover, rings, X, rule: FairnessRule, sharp=None,
              constraints=None):
    """(degrees (V,), fits :class:`gerbs_core.mesh.coupling.CoupledFits`): the coefficients
    of every vertex's local function, ``fits(X).reshape(V, MMAX, 3)``, in unscaled chart
    coordinates, chosen and coupled on the rest positions X (V, 3) as in the module
    docstring. sharp (F,): the faces' tension weights s_f (default :func:`tension_weights`);
    constraints: optional callable degrees (V,) -> linear constraints on the coefficients
    (:func:`gerbs_core.mesh.crease_fits.curve_constraints`) or None."""
    V = topo.n_vertices
    cands = candidate_fits_all(rings, rule.candidates)
    # the stars' spreads (degrees): the extra candidates' and the coupling weight's rule
    star = star_spread(topo, X)
    # extra candidates at spread stars (mesh.spread_fits): none on smooth meshes
    extra, spiky = spread_candidates(topo, charts, corners2d, rings, X, rule.spread, star) \
        if len(cands) > 1 else ([], None)
    cands = cands + extra
    if sharp is None:
        sharp = tension_weights(topo, X, rule)
    smp = _samples(topo, charts, corners2d, cover, rings.h, rule.resolution, sharp)
    coefs = penalty = None
    if len(cands) > 1:
        coefs = candidate_coefs(cands, X)
        penalty = _fold_penalty(cands, X, smp, face_normals(topo, X), rings.h, rule, coefs)
        penalty = gate(penalty, smp.vertex, len(extra), spiky)
        choice = _choose(cands, X, smp, rule, V, penalty, coefs)
    else:
        choice = np.zeros(V, np.int64)
    coupled = bool(rule.sweeps and (rule.mu or rule.lam))
    degrees, chosen, normals, rhs = _chosen_fits(cands, choice, V, coupled)
    # the candidates' operators, coefficients and penalties are not needed by the coupling:
    # freed before it (on a 35k-vertex mesh ~0.45 GB of the model's peak)
    del cands, extra, coefs, penalty
    cons = None if constraints is None else constraints(degrees)
    if not coupled:
        proj = None if cons is None else cons.projection(normals, rings.h, degrees, MMAX)
        return degrees, identity_fits(chosen, proj)
    return degrees, coupled_fits(chosen, rhs, normals, degrees, smp, rule, rings.h, DMAX,
                                 cons, mu=row_mu(topo, star, smp, rule))


def row_mu(topo, star, smp, rule: FairnessRule) -> np.ndarray | float:
    """The coupling's agreement weight: (SC,) per energy row, ``rule.spread_mu * rule.mu``
    on the faces of stars spreading above ``rule.spread_mu_from`` degrees (``star`` (V,)
    the vertices' spreads, :func:`gerbs_core.mesh.spread_fits.spread_faces`) and
    ``rule.mu`` elsewhere; the
    scalar ``rule.mu`` where no face qualifies (smooth meshes: bit-identical). A function
    of the rest shape only, so the fits stay linear in the positions."""
    if rule.spread_mu == 1.0 or rule.mu == 0.0:
        return rule.mu
    hit = spread_faces(topo, star, rule.spread_mu_from)
    if not hit.any():
        return rule.mu
    return np.where(hit[smp.face], rule.spread_mu * rule.mu, rule.mu)


def _chosen_fits(cands, choice, V, coupled):
    """(degrees (V,), chosen (V MMAX, V), normals (V, MMAX, MMAX), rhs (V MMAX, V) or None
    without coupling) of every vertex's chosen candidate ``choice`` (V,)."""
    degrees = np.array([c.degree for c in cands])[choice]
    chosen = _chosen(cands, choice, "matrix", V)
    normals = np.zeros((V, MMAX, MMAX))
    for i, c in enumerate(cands):
        mine = np.flatnonzero(choice == i)
        M = n_monomials(c.degree)
        normals[mine, :M, :M] = c.normal[mine]
    rhs = _chosen(cands, choice, "rhs", V) if coupled else None
    return degrees, chosen, normals, rhs
