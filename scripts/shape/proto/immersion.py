"""Prototype: the fold penalty also charges a candidate whose Jacobian degenerates in its
support: q(y) = 2 |J1 x J2| / (|J1|^2 + |J2|^2) (1 conformal, 0 singular) against q(0)."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
from gerbs_core.mesh.monomials import monomials, n_monomials  # noqa: E402
from gerbs_core.mesh.row_values import rows_apply  # noqa: E402

OPTS = {"gamma": 1000.0, "q0": 0.3, "keep_normal": True}


def penalty(cands, X, smp, fn, h, rule, coefs=None, _old=ag._fold_penalty):
    out = _old(cands, X, smp, fn, h, rule, coefs) if OPTS["keep_normal"] else 0.0
    dm = monomials(smp.y, max(c.degree for c in cands), 1)[1]
    extra = np.zeros((len(smp.vertex), len(cands)))
    for i, c in enumerate(cands):
        M = n_monomials(c.degree)
        coef = (c.matrix @ X).reshape(-1, 3)
        d1, d2 = (rows_apply(np.ascontiguousarray(dm[:, :M, j]), smp.vertex, coef)
                  for j in (0, 1))
        q = 2 * np.linalg.norm(np.cross(d1, d2), axis=1) / np.maximum(
            (d1 ** 2).sum(1) + (d2 ** 2).sum(1), 1e-300)
        c3 = coef.reshape(-1, M, 3)
        a, b = c3[:, 0], c3[:, 1]
        q0 = 2 * np.linalg.norm(np.cross(a, b), axis=1) / np.maximum(
            (a ** 2).sum(1) + (b ** 2).sum(1), 1e-300)
        extra[:, i] = np.maximum(0.0, OPTS["q0"] - q / np.maximum(q0[smp.vertex], 1e-12)) ** 2
    return out + (OPTS["gamma"] * h[smp.vertex] ** 2 * smp.weight * smp.psi)[:, None] * extra


def patched(**opts):
    return patching(OPTS, opts, [(ag, "_fold_penalty", penalty)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)
