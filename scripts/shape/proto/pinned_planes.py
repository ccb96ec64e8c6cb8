"""Prototype: where the coupling turns a vertex's tangent plane against one of its star
faces, keep the chosen data fit's tangent plane there (its linear coefficients) through
the coupling sweeps.

Why: the remaining folds of Suzanne's mouth corners are made by the coupling (none
without sweeps, docs/design.md "Folds"), and on MeshLab's cow 52 of the 55 pairs above
90 degrees lie in faces whose corner's coupled tangent plane (the normal of l_v's linear
part) turns more than 90 degrees against the face, while the uncoupled candidates there
are not turned (`folds.py --exact`). Near v, S = l_v, so such a plane folds the surface at
the vertex itself.

Rule: one build of the default coupled fits at the rest shape X; vertices where the
coupled tangent plane is turned more than ``angle`` degrees against a star face and the
chosen fit's is not are flagged; the coupling is built again with the linear constraints
c_v,(1,0) = chosen_v,(1,0) X, c_v,(0,1) = chosen_v,(0,1) X at those vertices (the crease
constraints' mechanism: imposed after the first fit and every sweep in the metric of the
coupled normal matrices). A function of the rest shape only: the surface stays linear in X
and constants map to zero (the chosen fits' rows sum to zero). Meshes with crease
constraints are left as they are.

Variants: ``p90`` (angle 90), ``p75``, ``p60``."""
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import scipy.sparse as sp

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, variant_of  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
import gerbs_core.mesh.surface as surface  # noqa: E402
from gerbs_core.mesh.crease_fits import CurveConstraints  # noqa: E402

OPTS = {"angle": 90.0, "ctx": (None, None), "flagged": None}
_coupled, _fair_fits = ag.coupled_fits, ag.fair_fits


def _unit(a):
    return a / np.maximum(np.linalg.norm(a, axis=-1, keepdims=True), 1e-300)


def _min_cos(coef, topo, fn, V, mmax):
    """(V,) the least cos between each vertex's tangent plane (coefficients (V MMAX, 3))
    and its star faces' rest normals."""
    c = coef.reshape(V, mmax, 3)
    n = _unit(np.cross(c[:, 0], c[:, 1]))
    fv, cf = np.asarray(topo.face_vertices), np.asarray(topo.corner_face)
    out = np.full(V, np.inf)
    np.minimum.at(out, fv, np.einsum("ij,ij->i", n[fv], fn[cf]))
    return out


def coupled_fits(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints=None, mu=None):
    fits = _coupled(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints, mu=mu)
    topo, X = OPTS["ctx"]
    if constraints is not None or topo is None:
        return fits
    V, mmax = len(degrees), ag.MMAX
    fn = ag.face_normals(topo, X)
    lim = np.cos(np.radians(OPTS["angle"]))
    flag = (_min_cos(fits(X), topo, fn, V, mmax) < lim) & \
        (_min_cos(chosen @ X, topo, fn, V, mmax) >= lim)
    OPTS["flagged"] = np.flatnonzero(flag)
    if not flag.any():
        return fits
    vs = np.flatnonzero(flag)
    rows = (vs[:, None] * mmax + np.arange(2)).ravel()
    K = sp.csr_matrix((np.ones(len(rows)), (np.arange(len(rows)), rows)),
                      shape=(len(rows), V * mmax))
    G = chosen.tocsr()[rows]
    cons = CurveConstraints(K, G, np.repeat(vs, 2))
    return _coupled(chosen, rhs, normals, degrees, smp, rule, h, dmax, cons, mu=mu)


def fair_fits(topo, charts, corners2d, cover, rings, X, *args, **kw):
    OPTS["ctx"] = (topo, X)
    try:
        return _fair_fits(topo, charts, corners2d, cover, rings, X, *args, **kw)
    finally:
        OPTS["ctx"] = (None, None)


@contextmanager
def patched(**opts):
    with patching(OPTS, opts, [(ag, "coupled_fits", coupled_fits),
                               (surface, "fair_fits", fair_fits)]):
        yield


p90, p75, p60 = (variant_of(patched, angle=a) for a in (90.0, 75.0, 60.0))
