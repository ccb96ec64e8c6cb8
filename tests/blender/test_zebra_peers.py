"""Issue 11's zebra item as a number: on Suzanne at matched density (r = 8 against 3
subdivision steps, 31,146 points each) the default surface's reflection-line stripes break
into fewer visible pieces than Modified Butterfly's (MeshLab), the other interpolating
scheme. Controls: Catmull-Clark, which smooths instead of interpolating and looks fairest
in docs/img/zebra_peers_suzanne.png, must have far fewer than Butterfly; the fairing,
which bounds turns and does not smooth, leaves the count within 5%."""
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.blender

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def pieces():
    import sys

    import bpy

    sys.path.insert(0, str(ROOT / "scripts"))
    try:
        from shape import methods
    finally:
        sys.path.remove(str(ROOT / "scripts"))
    from gerbs_core.datasets.obj import read_obj
    from gerbs_core.testing import stripe_components

    V, F = read_obj(ROOT / "examples" / "suzanne.obj")
    outs = {"default": methods.gerbs_samples(V, F, 8, exact=False),
            "no-fairing": methods.gerbs_samples(V, F, 8, exact=False,
                                                **methods.VARIANTS["no-fairing"]),
            "butterfly": methods.meshlab(V, F, "butterfly", 3),
            "catmull-clark": methods.catmull_clark(bpy, V, F, 3)}
    assert len(outs["default"]["points"]) == len(outs["butterfly"]["points"]) == 31146
    return {k: stripe_components(o["points"], np.asarray(o["triangles"])) for k, o in outs.items()}


def test_suzanne_stripes_in_no_more_visible_pieces_than_butterfly(pieces):
    # measured 2026-12-06 (pieces of >= 1e-3 of the area, per direction): default 167.2,
    # no-fairing 168, Butterfly 181.9, Catmull-Clark 107.9. Smaller pieces (>= 1e-4):
    # 700, 690, 691, 253 -- there GERBS is no better than Butterfly (docs/design.md)
    assert 150 < pieces["default"] < 0.95 * pieces["butterfly"]   # (the area floor, the stripes)
    assert 170 < pieces["butterfly"] < 195 and 95 < pieces["catmull-clark"] < 120
    assert pieces["catmull-clark"] < 0.7 * pieces["butterfly"]
    assert abs(pieces["default"] - pieces["no-fairing"]) < 0.05 * pieces["default"]
