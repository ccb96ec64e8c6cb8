"""The interpolator where the points sit and how large they are: the Delaunay
triangulation is computed on centred, power-of-two scaled coordinates (translation and
scale invariant; ordinary point sets keep Qhull's triangulation to the bit), and point
sets whose extent is outside the supported range are refused naming ``points`` and
the range.

Found by a review: points 0.05 apart offset by 1e5 / 1e6 were refused as "numerically
coincident" (Qhull on raw coordinates); scale 1e100 gave a false "degenerate
(collinear)"; scale 1e160 with balls a raw IndexError (radii.py), 1e-160 an error
naming ``rho``, which the caller never passed.
"""
import numpy as np
import pytest
from scipy.spatial import Delaunay

from gerbs_core import GERBSInterpolator
from gerbs_core.errors import InvalidPointSetError

RNG = np.random.default_rng(2)
P = RNG.random((120, 2))
F = np.sin(3 * P[:, 0]) * np.cos(2 * P[:, 1])
Q = 0.2 + 0.6 * RNG.random((20, 2))
P3 = RNG.random((60, 3))
F3 = np.sin(P3).sum(1)
Q3 = 0.3 + 0.4 * RNG.random((20, 3))


def _case(cover):
    return (P3, F3, Q3, "delaunay") if cover == "delaunay3" else (P, F, Q, cover)


@pytest.mark.parametrize("cover", ["delaunay", "voronoi", "balls", "delaunay3"])
@pytest.mark.parametrize("offset", [1e5, 1e6])
def test_far_offset_points_give_the_same_interpolant(cover, offset):
    pts, f, q, c = _case(cover)
    ref = GERBSInterpolator(pts, f, cover=c)(q)
    got = GERBSInterpolator(pts + offset, f, cover=c)(q + offset)
    # (the shifted coordinates themselves are rounded at offset * 1.1e-16)
    assert np.abs(got - ref).max() < 1e-12 * offset


@pytest.mark.parametrize("cover", ["delaunay", "voronoi", "balls", "delaunay3"])
@pytest.mark.parametrize("scale", [1e-90, 1e90])
def test_extreme_scales_inside_the_range_give_the_same_interpolant(cover, scale):
    pts, f, q, c = _case(cover)
    I1 = GERBSInterpolator(pts, f, cover=c)
    Is = GERBSInterpolator(pts * scale, f, cover=c)
    for nu in range(3):
        ref = I1(q, nu)
        got = Is(q * scale, nu) * scale ** nu
        assert np.abs(got - ref).max() <= 1e-9 * np.abs(ref).max()


@pytest.mark.parametrize("scale", [1e160, 1e-160, 1e120])
@pytest.mark.parametrize("cover", ["delaunay", "balls"])
def test_extents_outside_the_range_are_refused_naming_points(cover, scale):
    with pytest.raises(InvalidPointSetError, match=r"^points: the extent .* outside the "
                       r"supported range \[1e-100, 1e\+100\]"):
        GERBSInterpolator(P * scale, F, cover=cover)


def test_lp_metrics_with_high_powers_have_a_narrower_range():
    GERBSInterpolator(P * 1e30, F, cover="balls", metric=("lp", 8))        # 1e35 allowed
    with pytest.raises(InvalidPointSetError, match=r"points: .* \[1e-35, 1e\+35\] for the "
                       r"l_p metric with p = 8"):
        GERBSInterpolator(P * 1e40, F, cover="balls", metric=("lp", 8))


def test_ordinary_point_sets_keep_qhulls_triangulation_to_the_bit():
    """Boxes near the origin (any size): the map is a power-of-two scaling, so Qhull
    triangulates exactly as it does the points themselves, co-circular grids included;
    transforms and point location answer in the caller's coordinates."""
    from gerbs_core.scattered.triangulation import delaunay
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 9), np.linspace(0, 1, 9)), -1).reshape(-1, 2)
    for pts in (P, grid, grid * 1e-7 + 3e-7, P3 * 50.0, grid + 10.0):
        tri, ref = delaunay(pts), Delaunay(pts)
        assert np.array_equal(tri.simplices, ref.simplices)
        assert np.array_equal(tri.neighbors, ref.neighbors)
        x = pts.min(0) + (pts.max(0) - pts.min(0)) * (1.2 * RNG.random((300, pts.shape[1])) - 0.1)
        assert np.array_equal(tri.find_simplex(x), ref.find_simplex(x))
        np.testing.assert_allclose(tri.transform, ref.transform, rtol=1e-12,
                                   atol=1e-12 * np.abs(ref.transform).max())


def test_far_boxes_are_triangulated_next_to_the_origin():
    from gerbs_core.scattered.triangulation import delaunay
    tri = delaunay(P + 1e6)
    assert np.abs(tri.qhull.points).max() <= 32.5
    assert set(map(tuple, np.sort(tri.simplices, 1))) == \
        set(map(tuple, np.sort(Delaunay(P).simplices, 1)))
    # location in the caller's coordinates
    t = tri.find_simplex(Q + 1e6)
    lam = np.einsum("mij,mj->mi", tri.transform[t, :2], Q + 1e6 - tri.transform[t, 2])
    assert lam.min() >= -1e-6 and (1 - lam.sum(1)).min() >= -1e-6


def test_points_coincident_to_the_metric_are_named_not_rho():
    """Two points 1e-320 apart: distinct, but their distance squares to 0, so the automatic
    radii would be 0; the error names the points (was: "rho: radii must be finite and
    > 0", although the caller passed no rho)."""
    pts = P[:30].copy()
    pts[0], pts[1] = [0.0, 0.0], [1e-320, 0.0]
    with pytest.raises(InvalidPointSetError, match=r"^points: numerically coincident in the "
                       r"metric \(nearest distance 0\)") as exc:
        GERBSInterpolator(pts, pts.sum(1), cover="balls", degree=1)
    assert exc.value.indices == (0, 1)
