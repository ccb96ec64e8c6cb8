"""Prototype: stronger (or weaker) coupling on the faces of vertices whose cage star spreads
(largest angle between a star face's normal and the vertex's mean normal) above
``spread`` degrees: their rows' weights times ``beta`` in the coupling sweeps."""
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, run_variant  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
import gerbs_core.mesh.coupling as cp  # noqa: E402
from gerbs_core.mesh.spread_fits import spread_faces, star_spread  # noqa: E402

OPTS = {"beta": 3.0, "spread": 60.0, "topo": None, "X": None, "rows": "face"}


def coupled(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints=None, mu=None, _old=cp.coupled_fits):
    topo, X = OPTS["topo"], OPTS["X"]
    if OPTS["rows"] == "face":
        hit = spread_faces(topo, star_spread(topo, X), OPTS["spread"])[smp.face]
    else:
        hit = (star_spread(topo, X) > OPTS["spread"])[smp.vertex]
    smp = dataclasses.replace(smp, weight=smp.weight * np.where(hit, OPTS["beta"], 1.0))
    return _old(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints, mu=mu)


def fair_fits(topo, charts, corners2d, cover, rings, X, rule, sharp=None, constraints=None,
              _old=ag.fair_fits):
    OPTS["topo"], OPTS["X"] = topo, X
    return _old(topo, charts, corners2d, cover, rings, X, rule, sharp, constraints)


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", fair_fits), (ag, "coupled_fits", coupled)])


def variant(V, F, r, exact=True, **opts):
    """bench_shape prototype variant: the default surface with this module's change."""
    return run_variant(patched, V, F, r, exact=exact, **opts)
