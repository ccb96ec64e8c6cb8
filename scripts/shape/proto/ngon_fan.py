"""Prototype: a face point in every n-gon (issue 11's lever "data where the vertices are
far"), the n-gon fanned into triangles about it.

The face point is the mean of the face's corners (a fixed linear rule, so the output
stays a fixed sparse linear function of the positions) and the surface passes through
it. Measured against the default's n-gon lattice, where every corner of an n-gon is
active almost everywhere in it (a 128-gon cap: 78 of 128 corners at a cap sample on
average, every output row of the 128-vertex Cylinder reads all 256 vertices), so the
stencil is dense and the build superlinear in n (Cylinder 32 / 128 / 256 sides:
0.3 / 2.7 / 15.7 s at r = 4; 256 sides at r = 8 refused by the memory budget).

``MIN_SIDES``: the smallest face that gets a face point (5: pentagons and up).
"""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.methods import gerbs_samples  # noqa: E402

MIN_SIDES = 5


def fanned(V, F, min_sides=MIN_SIDES):
    """(V' (V + m, 3), F' faces): the mesh with a centroid vertex in each face of at least
    ``min_sides`` corners and that face replaced by its fan (v_k, v_k+1, c)."""
    V = np.asarray(V, dtype=np.float64)
    extra, out = [], []
    for f in F:
        f = [int(i) for i in f]
        if len(f) < min_sides:
            out.append(f)
            continue
        c = len(V) + len(extra)
        extra.append(V[f].mean(0))
        out.extend([f[k], f[(k + 1) % len(f)], c] for k in range(len(f)))
    return (np.vstack([V, np.array(extra)]) if extra else V), out


def variant(V, F, r, exact=True):
    V2, F2 = fanned(V, F)
    return gerbs_samples(V2, F2, r, exact=exact)


def variant8(V, F, r, exact=True):
    V2, F2 = fanned(V, F, 8)
    return gerbs_samples(V2, F2, r, exact=exact)


def _with(**rule):
    import gerbs_core

    def run(V, F, r, exact=True):
        V2, F2 = fanned(V, F)
        return gerbs_samples(V2, F2, r, exact=exact, fairness=gerbs_core.FairnessRule(**rule))
    return run


lam30 = _with(lam=30.0)
lam10 = _with(lam=10.0)
lam0 = _with(lam=0.0)
