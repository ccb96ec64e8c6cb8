"""Prototype: a fold penalty on the BLEND S in the choice, not on each candidate.

The fold penalty of the choice (gerbs_core.mesh.agreement) charges a candidate l_v that
turns against the face it is blended over; the agreement energy charges disagreement.
Neither sees a blend S = sum Psi_k l_k whose normal turns where several local functions
overlap although each one is fair (Suzanne's mouth corners: vertex 139's cubic has fold
penalty 0.007, yet the output turns by 117 degrees 0.3 edges from it). Here every choice
round also charges candidate i of vertex v, at each energy row (sample p, v),

    beta h_v^2 w Psi_v max(0, cos0 - n_S(p) . n_f)^2,

n_S the unit normal of dS/dx1 x dS/dx2 at p with v's candidate i and every other vertex's
current choice (dS = sum_k dPsi_k l_k + Psi_k dl_k, face layout coordinates), n_f the
rest normal of p's face. Only the choice changes (on the rest shape): the output stays the
same kind of linear map of X. Measured in docs/design.md ("Folds")."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
from gerbs_core.gauge.jet import partition_jet  # noqa: E402
from gerbs_core.mesh.monomials import monomials, n_monomials  # noqa: E402

OPTS = {"beta": 1000.0, "cos0": 0.0, "ctx": None, "rows": None}


def row_jets(topo, charts, corners2d, cover, smp, resolution):
    """(dPsi (SC, 2), J (SC, 2, 2)): the rows' partition gradients and chart Jacobians
    dy/dx in face layout coordinates (the rows of ag._samples)."""
    from gerbs_core.mesh.lattice import Lattice
    x = Lattice(topo, resolution).map_to_polygon(corners2d, local=True)[smp.sample]
    f, v = smp.face, smp.vertex
    fo, fs = topo.face_offsets[f], topo.face_sizes[f]
    corner = np.full(len(f), -1)
    for k in range(int(fs.max())):
        c = fo + np.minimum(k, fs - 1)
        corner = np.where((corner < 0) & (topo.face_vertices[c] == v), c, corner)
    dpsi = np.zeros((len(f), 2))
    for n in np.unique(fs).tolist():
        r = np.flatnonzero(fs == n)
        cb = fo[r][None, :] + np.arange(n)[:, None]                  # (n, R)
        psi, _ = cover.psi_jet(charts, cb, x[r][None], 1)
        P = partition_jet(psi, 1)
        slot = corner[r] - fo[r]
        dpsi[r] = P[1][slot, np.arange(len(r))]
    J = charts.to_chart(corner, x, 1)[1]
    return dpsi, J


def samples(topo, charts, corners2d, cover, h, resolution, sharp_face, _old=ag._samples):
    smp = _old(topo, charts, corners2d, cover, h, resolution, sharp_face)
    OPTS["rows"] = row_jets(topo, charts, corners2d, cover, smp, resolution)
    OPTS["h"] = h
    return smp


def _blend_terms(cands, coefs, smp, vals):
    """G (SC, ncand, 3, 2): row s's term dPsi l + Psi dl/dx of every candidate."""
    dpsi, J = OPTS["rows"]
    dm = monomials(smp.y, max(c.degree for c in cands), 1)[1]        # (SC, M, 2)
    G = np.empty(vals.shape + (2,))
    for i, c in enumerate(cands):
        M = n_monomials(c.degree)
        C = coefs[i].reshape(-1, M, 3)[smp.vertex]                     # (SC, M, 3)
        dl = np.einsum("smj,smc->scj", dm[:, :M], C) @ J               # (SC, 3, 2)
        G[:, i] = vals[:, i, :, None] * dpsi[:, None, :] + smp.psi[:, None, None] * dl
    return G


def choose(cands, X, smp, rule, V, penalty, coefs=None):
    """ag._choose with the blend's fold penalty added in every round."""
    coefs = ag.candidate_coefs(cands, X) if coefs is None else coefs
    vals = ag.candidate_values(cands, X, smp.vertex, smp.Bu, coefs)
    cage = (smp.cage @ X)[smp.sample]
    P = smp.psi
    tension = (rule.lam * (smp.sharp * P)[:, None] * ((vals - cage[:, None]) ** 2).sum(-1)
               + penalty)
    one = 1.0 - P
    scale = np.where(one > 1e-12, P / np.where(one > 1e-12, one, 1.0), 0.0)
    G = _blend_terms(cands, coefs, smp, vals)
    nf = OPTS["fn"][smp.face]
    wb = OPTS["beta"] * OPTS["h"][smp.vertex] ** 2 * smp.weight * P
    rows = np.arange(len(P))
    choice = np.zeros(V, dtype=np.int64)
    for _ in range(rule.choice_rounds):
        cur = P[:, None] * vals[rows, choice[smp.vertex]]
        S = np.stack([np.bincount(smp.sample, cur[:, k], minlength=smp.n_samples)
                      for k in range(3)], 1)
        others = S[smp.sample] - cur
        gap = one[:, None, None] * vals - others[:, None, :]
        energy = scale[:, None] * (gap ** 2).sum(-1) + tension
        Gc = G[rows, choice[smp.vertex]]                                # (SC, 3, 2)
        dS = np.stack([np.bincount(smp.sample, Gc[:, k, j], minlength=smp.n_samples)
                       for k in range(3) for j in range(2)], 1).reshape(-1, 3, 2)
        dSi = dS[smp.sample][:, None] - Gc[:, None] + G                 # (SC, ncand, 3, 2)
        n = np.cross(dSi[..., 0], dSi[..., 1])
        n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-300)
        fold = np.maximum(0.0, OPTS["cos0"] - np.einsum("sic,sc->si", n, nf)) ** 2
        energy = energy + wb[:, None] * fold
        E = np.stack([np.bincount(smp.vertex, energy[:, i], minlength=V)
                      for i in range(len(cands))], 1)
        new = ag.first_minimum(E)
        if np.array_equal(new, choice):
            break
        choice = new
    return choice


def fair_fits(topo, charts, corners2d, cover, rings, X, rule, sharp=None, constraints=None,
              _old=ag.fair_fits):
    OPTS["fn"] = ag.face_normals(topo, X)
    return _old(topo, charts, corners2d, cover, rings, X, rule, sharp, constraints)


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", fair_fits), (ag, "_samples", samples),
                                 (ag, "_choose", choose)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)


def b1000(V, F, r, exact=True):
    """Variant: the blend's fold penalty at weight 1000, cos0 0."""
    return variant(V, F, r, exact=exact, beta=1000.0, cos0=0.0)
