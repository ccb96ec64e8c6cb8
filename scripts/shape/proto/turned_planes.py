"""Prototype: the choice may not take a candidate whose tangent plane at its vertex is
turned more than ``angle`` degrees against one of the faces it is blended over, where
another candidate is not (then the turned ones get an infinite energy; where every
candidate is turned the choice is left alone).

Why: near v, S = l_v (Psi_v = 1), so a local function whose tangent plane at v (the
normal of its linear part, cross(c_y1, c_y2)) points away from a star face's rest normal
folds the surface at the vertex itself; on MeshLab's cow 21 of the 45 corners turned
against their face had an unturned candidate the choice did not take (`folds.py --exact`,
docs/design.md "Folds"). The faces are the sample rows' faces of each vertex (its star
faces). A function of the rest shape only: the surface stays linear in X.

Variants: ``t90`` (angle 90), ``t75``, ``t105``."""
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, variant_of  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
import gerbs_core.mesh.surface as surface  # noqa: E402

OPTS = {"angle": 90.0, "topo": None, "excluded": None}
_choose, _fair_fits = ag._choose, ag.fair_fits


def turned(cands, coefs, X, smp, topo, V, angle):
    """(V, ncand) bool: candidate i's tangent plane at v turned more than ``angle``
    degrees against some face of v's sample rows."""
    fn = ag.face_normals(topo, X)
    cmin = np.full((V, len(cands)), np.inf)
    for i, c in enumerate(cands):
        M = ag.n_monomials(c.degree)
        co = coefs[i].reshape(V, M, 3)
        n = np.cross(co[:, 0], co[:, 1])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
        cos = np.einsum("ij,ij->i", n[smp.vertex], fn[smp.face])
        np.minimum.at(cmin[:, i], smp.vertex, cos)
    return cmin < np.cos(np.radians(angle))


def choose(cands, X, smp, rule, V, penalty, coefs=None):
    coefs = ag.candidate_coefs(cands, X) if coefs is None else coefs
    bad = turned(cands, coefs, X, smp, OPTS["topo"], V, OPTS["angle"])
    # only where some candidate is not turned and may be chosen (finite penalty)
    E = np.stack([np.bincount(smp.vertex, penalty[:, i], minlength=V)
                  for i in range(len(cands))], 1)
    ok = ~bad & np.isfinite(E)
    shut = bad & ok.any(1, keepdims=True)
    OPTS["excluded"] = shut
    penalty = penalty.copy()
    penalty[shut[smp.vertex]] = np.inf
    return _choose(cands, X, smp, rule, V, penalty, coefs)


def fair_fits(topo, *args, **kw):
    OPTS["topo"] = topo
    return _fair_fits(topo, *args, **kw)


@contextmanager
def patched(**opts):
    with patching(OPTS, opts, [(ag, "_choose", choose), (surface, "fair_fits", fair_fits)]):
        yield


t90, t75, t105 = (variant_of(patched, angle=a) for a in (90.0, 75.0, 105.0))
