"""Prototype: a sharpness-dependent agreement weight in the coupling (issue 11). Each
sample row's mu is mu_row = mu_smooth (1 - s) + mu_sharp s for its face sharpness s
(``smp.sharp``, rest shape), instead of the rule's one ``mu``: the stronger agreement
that helps the folds and the smooth inputs (mu 450, docs/design.md "Folds") without the
Cube's and the Cylinder's growth (their faces are all fully sharp: mu_sharp there).

The coupling (:func:`gerbs_core.mesh.coupling.coupled_fits`) takes a per-row ``mu``;
this prototype's replaces the default's. mu_row depends on the rest shape only, so the
map stays linear in X. The choice (:func:`gerbs_core.mesh.agreement._choose`) does not read mu (its
agreement is unweighted against lam * tension): untouched.

Measured (docs/design.md "Folds"): the Cube's, the Cylinder's and the Cone's faces are
all fully sharp, so those are bit for bit the default's, but mu_smooth alone (s450-s600)
gives none of mu 450's fold gain: it lies on the sharp rows (the reverse, r450, has all of
it and the Cube's 1.48). What separates the folds from the primitives' rims is the cage
star's spread (``mu_spread``: the rows on faces of stars above ``spread`` degrees, the
Cylinder's rim and the Cone's apex 63.4, the Cube's corners 54.7): sp450t70, the
default since 2026-12-04 (FairnessRule.spread_mu, spread_mu_from)."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[3]))
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.patching import patching, variant_of  # noqa: E402
import gerbs_core.mesh.agreement as ag  # noqa: E402
import gerbs_core.mesh.coupling as cp  # noqa: E402
from shape.proto import spread_coupling as SC  # noqa: E402  (its fair_fits keeps topo, X)

# rows: "row" (each row's own face sharpness) or "vertex" (the largest over the vertex's
# rows: a vertex touching a sharp face keeps mu_sharp on all its rows); mu_spread (None:
# off): the mu of the rows on faces touching a vertex whose cage star spreads above
# ``spread`` degrees (mesh.spread_fits.star_spread: the folds' vertices), whatever s
OPTS = {"mu_smooth": 450.0, "mu_sharp": 300.0, "rows": "row", "mu_spread": None,
        "spread": 60.0}


def row_mu(smp, mu_smooth: float, mu_sharp: float, rows: str = "row") -> np.ndarray:
    """(SC,) mu of every sample row: mu_smooth (1 - s) + mu_sharp s."""
    s = smp.sharp
    if rows == "vertex":
        top = np.zeros(int(smp.vertex.max()) + 1)
        np.maximum.at(top, smp.vertex, s)
        s = top[smp.vertex]
    return mu_smooth * (1.0 - s) + mu_sharp * s


def coupled(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints=None, mu=None,
            _old=cp.coupled_fits):
    """coupled_fits with this prototype's per-row mu (module docstring), in place of the
    default's (gerbs_core.mesh.agreement.row_mu, which promoted sp450t70)."""
    if rule.mu <= 0:
        return _old(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints, mu=mu)
    mu = row_mu(smp, OPTS["mu_smooth"], OPTS["mu_sharp"], OPTS["rows"])
    if OPTS["mu_spread"] is not None:
        topo = SC.OPTS["topo"]
        hit = SC.spread_faces(topo, SC.star_spread(topo, SC.OPTS["X"]), OPTS["spread"])
        mu = np.where(hit[smp.face], OPTS["mu_spread"], mu)
    return _old(chosen, rhs, normals, degrees, smp, rule, h, dmax, constraints, mu=mu)


def patched(**opts):
    import gerbs_core.mesh.surface as su
    return patching(OPTS, opts, [(su, "fair_fits", SC.fair_fits), (ag, "coupled_fits", coupled)])


variant = variant_of(patched)
s450 = variant_of(patched, mu_smooth=450.0)
s525 = variant_of(patched, mu_smooth=525.0)
s600 = variant_of(patched, mu_smooth=600.0)
s600v = variant_of(patched, mu_smooth=600.0, rows="vertex")
# the reverse (diagnostic: where mu 450's fold gain comes from)
r450 = variant_of(patched, mu_smooth=300.0, mu_sharp=450.0)
# mu 450 only on the faces of spread stars (the folds'); with 450 on smooth faces too
sp450 = variant_of(patched, mu_smooth=300.0, mu_spread=450.0)
sp600 = variant_of(patched, mu_smooth=300.0, mu_spread=600.0)
s450sp450 = variant_of(patched, mu_smooth=450.0, mu_spread=450.0)
# spread threshold above the Cylinder's rim and the Cone's apex (63.4 degrees)
sp450t70 = variant_of(patched, mu_smooth=300.0, mu_spread=450.0, spread=70.0)
sp450t65 = variant_of(patched, mu_smooth=300.0, mu_spread=450.0, spread=65.0)
s450sp450t70 = variant_of(patched, mu_smooth=450.0, mu_spread=450.0, spread=70.0)
sp600t70 = variant_of(patched, mu_smooth=300.0, mu_spread=600.0, spread=70.0)
