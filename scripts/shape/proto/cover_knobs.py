"""Prototype: the star cover's envelope knobs (gerbs_core.BlendingSurface ``kappa``, the
envelope's least reach against the star's, default 0.8; ``shrink``, its margin inside the
star, default 0.95) as bench_shape variants: wider supports blend neighbouring local
functions over more of each face, so a local function turned against a face (the cow's
folds, docs/design.md "Folds") turns the surface over more output triangles."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from shape.methods import gerbs_samples  # noqa: E402


def _variant(**opts):
    def f(V, F, r, exact=True):
        return gerbs_samples(V, F, r, exact=exact, **opts)
    return f


kappa90 = _variant(kappa=0.9)
kappa95 = _variant(kappa=0.95)
shrink97 = _variant(shrink=0.97)
kappa90_shrink97 = _variant(kappa=0.9, shrink=0.97)
