"""Kernels whose 1 - F(t) is 0 before t = 1 leave holes in every cover: the interpolator
refuses them where a query falls into one, with BlendingSurface's error (one rule,
gerbs_core.mesh.cover.require_cover), instead of returning fill_value inside the hull;
``cover_guaranteed`` never claims a cover with holes; ``R``, ``rho`` and
``cover_guaranteed`` answer on every cover, with the documented shapes.

Found by a review: ERBS(gamma=7.4, lam=0, sigma=0) gave NaN at 75 % of the points inside
the hull (delaunay), Step() at 44 %, and balls' cover_guaranteed said True; on the star
covers cover_guaranteed raised AttributeError, R had one entry per star edge (555 for
100 points) or raised AttributeError (R^3).
"""
import numpy as np
import pytest

from gerbs_core import ERBS, GERBSInterpolator, Step, cover_report
from gerbs_core.errors import InvalidParameterError

RNG = np.random.default_rng(0)
P2 = RNG.random((60, 2))
P3 = RNG.random((50, 3))
SQUARE = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]) * 0.12
HOLEY = [ERBS(gamma=7.4, lam=0.0, sigma=0.0), Step()]
COVERS = ["delaunay", "voronoi", "balls", "delaunay3", "polygons", "balls-l1"]


def _interp(cover, kernel=None, **kw):
    P = P3 if cover == "delaunay3" else P2
    c = {"delaunay3": "delaunay", "polygons": [p + SQUARE for p in P2],
         "balls-l1": "balls"}.get(cover, cover)
    if cover == "balls-l1":
        kw["metric"] = "l1"
    return GERBSInterpolator(P, np.sin(P).sum(1), cover=c, kernel=kernel, degree=1, **kw)


def _inside(I, m=4000):
    """Points of the hull (a sample of the cover's own domain)."""
    lam = np.random.default_rng(1).dirichlet(np.ones(I.n + 1), size=m)
    from gerbs_core.scattered.radii import simplicialization
    S = simplicialization(I.points)
    return np.einsum("mk,mkn->mn", lam, I.points[S[np.arange(m) % len(S)]])


@pytest.mark.parametrize("kernel", HOLEY, ids=repr)
@pytest.mark.parametrize("cover", COVERS)
def test_a_kernel_with_holes_is_refused_where_a_query_falls_in_one(cover, kernel):
    I = _interp(cover, kernel)
    assert I.cover_guaranteed is False
    with pytest.raises(InvalidParameterError, match="leaves holes in the cover") as exc:
        I(_inside(I))
    assert exc.value.name == "kernel"
    with pytest.raises(InvalidParameterError, match="leaves holes in the cover"):
        I.basis(_inside(I), nu=1)
    # far outside the domain: still the fill value, no error
    assert np.isnan(I(np.full((1, I.n), 50.0))).all()


@pytest.mark.parametrize("cover", COVERS)
def test_kernels_without_holes_are_unchanged(cover):
    I = _interp(cover)
    x = _inside(I)
    v = I(x)
    if cover != "polygons":                       # (user squares need not cover the hull)
        assert I.cover_guaranteed is True and np.isfinite(v).all()
    assert cover_report(I)["eps0"] >= 0           # the diagnostic still reports, never raises
    assert np.isnan(I(np.full((1, I.n), 50.0))).all()


def test_cover_guaranteed_follows_the_certified_gauge_bound():
    """b(t) at the cover's bound decides: Step(0.9) is positive up to 0.9 (guaranteed on
    every cover), Step(0.6) vanishes beyond 0.6 (the 0.66 - 0.9 bounds fail)."""
    for cover, t in (("delaunay", (2 / 3) / 0.76), ("voronoi", 0.5 / 0.76), ("balls", 0.9),
                     ("delaunay3", 0.75 / (0.5 * (1 + 0.75)))):
        assert _interp(cover).cover.max_gauge == pytest.approx(t)
        assert _interp(cover, Step(0.9)).cover_guaranteed is True
        assert _interp(cover, Step(0.6)).cover_guaranteed is False
    assert _interp("polygons").cover_guaranteed is False          # no certificate
    assert _interp("balls", R=0.3).cover_guaranteed is False      # user radii


@pytest.mark.parametrize("cover", COVERS)
def test_radii_and_guarantee_answer_on_every_cover(cover):
    I = _interp(cover)
    N = len(I.points)
    assert isinstance(I.cover_guaranteed, bool)
    assert I.R.shape == (N,) and I.rho.shape == (N,)
    assert np.all(I.rho > 0) and np.all(I.R >= I.rho)
    # R bounds the support: no basis function reaches beyond R_i from its point
    x = I.points[:, None, :] + I.R[:, None, None] * (1 + 1e-9) * np.array(
        [[np.cos(a), np.sin(a)] + [0.0] * (I.n - 2) for a in np.linspace(0, 6, 7)])
    x = x.reshape(-1, I.n)
    owner = np.repeat(np.arange(N), 7)
    idx, B, _, _ = I.basis(x[np.isfinite(I(x))])
    own = owner[np.isfinite(I(x))]
    hit = (idx == own[:, None]) & (B > 0)
    assert not hit.any()
