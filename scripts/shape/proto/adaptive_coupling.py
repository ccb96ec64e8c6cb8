"""Prototype: per-vertex coupling weights adapted on the rest shape -- where the coupled
local function turns against its faces more than its chosen data fit did, scale that
vertex's agreement and tension rows by ``alpha`` and couple again (``passes`` times)."""
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
from gerbs_core.mesh.coupling import coupled_fits  # noqa: E402
from gerbs_core.mesh.fits import candidate_fits_all  # noqa: E402
from gerbs_core.mesh.monomials import monomials, n_monomials  # noqa: E402
from gerbs_core.mesh.row_values import rows_apply  # noqa: E402

OPTS = {"alpha": 0.3, "passes": 1, "c0": 0.3, "margin": 0.2}


def vertex_cos(coef, degrees, smp, fn, V):
    """(V,) least cos(normal of l_v, face normal) over the vertex's rows."""
    coef = np.asarray(coef).reshape(V * ag.MMAX, 3)
    dm = monomials(smp.y, ag.DMAX, 1)[1]
    d = [rows_apply(np.ascontiguousarray(dm[:, :, j]), smp.vertex, coef) for j in (0, 1)]
    n = np.cross(d[0], d[1])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    cs = np.einsum("ij,ij->i", n, fn[smp.face])
    out = np.ones(V)
    np.minimum.at(out, smp.vertex, cs)
    return out


def fair_fits(topo, charts, corners2d, cover, rings, X, rule, sharp=None, constraints=None):
    V = topo.n_vertices
    cands = candidate_fits_all(rings, rule.candidates)
    if sharp is None:
        sharp = ag.face_sharpness(topo, X, rule.sharp_from, rule.sharp_to)
    smp = ag._samples(topo, charts, corners2d, cover, rings.h, rule.resolution, sharp)
    fn = ag.face_normals(topo, X)
    penalty = ag._fold_penalty(cands, X, smp, fn, rings.h, rule)
    choice = ag._choose(cands, X, smp, rule, V, penalty)
    degrees = np.array([c.degree for c in cands])[choice]
    chosen = ag._chosen(cands, choice, "matrix", V)
    normals = np.zeros((V, ag.MMAX, ag.MMAX))
    for i, c in enumerate(cands):
        mine = np.flatnonzero(choice == i)
        M = n_monomials(c.degree)
        normals[mine, :M, :M] = c.normal[mine]
    rhs = ag._chosen(cands, choice, "rhs", V)
    fits = coupled_fits(chosen, rhs, normals, degrees, smp, rule, rings.h, ag.DMAX, None)
    base = vertex_cos(chosen @ X, degrees, smp, fn, V)
    alpha = np.ones(V)
    for _ in range(OPTS["passes"]):
        cur = vertex_cos(fits(X), degrees, smp, fn, V)
        bad = (cur < OPTS["c0"]) & (cur < base - OPTS["margin"])
        if not bad.any():
            break
        alpha[bad] *= OPTS["alpha"]
        smp2 = dataclasses.replace(smp, weight=smp.weight * alpha[smp.vertex])
        fits = coupled_fits(chosen, rhs, normals, degrees, smp2, rule, rings.h, ag.DMAX, None)
    return degrees, fits


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", fair_fits)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)
