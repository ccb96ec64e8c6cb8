"""GERBSInterpolator at the edges of its input: every bad setting or cover raises the
specific error naming it; the unusual but valid inputs (one point with a given R, points
as a 1-d array, balls in R^7 where no simplicialization certifies R) still give an
interpolant of the data.
"""
import numpy as np
import pytest

from gerbs_core import GERBSInterpolator
from gerbs_core.errors import InvalidParameterError, InvalidPointSetError
from gerbs_core.scattered.metrics import Euclidean

RNG = np.random.default_rng(0)
P2 = RNG.uniform(0.0, 1.0, (30, 2))
V2 = np.sin(P2).sum(1)
SQUARE = np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]])


@pytest.mark.parametrize("kw, name", [
    (dict(chunk_size=0), "chunk_size"), (dict(memory_budget=0), "memory_budget"),
    (dict(degree=2, fit_degree=1), "fit_degree"), (dict(cover="nope"), "cover"),
    (dict(basis="nope"), "basis"), (dict(metric="manhattan"), "metric"),
    (dict(kappa=1.2), "kappa"), (dict(kappa=0.0), "kappa"), (dict(shrink=0.0), "shrink"),
    (dict(cover=[p + SQUARE for p in P2[:-1]]), "cover"),
    (dict(cover="voronoi", domain=np.zeros((2, 2))), "domain"),
    (dict(degree=2, n_neighbors=3), "n_neighbors"),
])
def test_bad_settings_name_the_argument(kw, name):
    with pytest.raises(InvalidParameterError) as exc:
        GERBSInterpolator(P2, V2, **kw)
    assert exc.value.name == name


def test_user_polygons_that_are_too_small_are_named():
    polys = [p + SQUARE for p in P2]
    polys[2] = np.zeros((2, 2))
    with pytest.raises(InvalidPointSetError, match="need >= 3 finite vertices") as exc:
        GERBSInterpolator(P2, V2, cover=polys)
    assert exc.value.indices == (2,)


def test_numerically_coincident_plane_points_are_named():
    p = P2.copy()
    p[5] = p[4] * (1 + 1e-15)
    with pytest.raises(InvalidPointSetError, match="numerically coincident") as exc:
        GERBSInterpolator(p, V2)
    assert exc.value.indices == (5,)


def test_one_point_needs_a_radius():
    with pytest.raises(InvalidPointSetError, match="needs R when N < 2"):
        GERBSInterpolator(P2[:1], V2[:1], cover="balls", degree=0)
    s = GERBSInterpolator(P2[:1], V2[:1], cover="balls", R=0.5, degree=0)
    assert np.isinf(s.cover.nearest).all()
    x = P2[0] + np.array([[0.0, 0.0], [0.2, 0.0], [0.0, 0.6]])
    out = s(x)
    np.testing.assert_array_equal(out[:2], V2[0])          # the constant inside its ball
    assert np.isnan(out[2])                                 # outside: fill_value


def test_points_as_a_1d_array_are_points_on_the_line():
    x = np.array([0.0, 1.0, 2.0, 3.0])
    s = GERBSInterpolator(x, x ** 2, degree=0)
    assert s.points.shape == (4, 1)
    np.testing.assert_array_equal(s(x[:, None]), x ** 2)


def test_balls_in_r7_without_a_certificate_still_interpolate():
    p = RNG.uniform(0.0, 1.0, (20, 7))
    v = RNG.normal(size=20)
    s = GERBSInterpolator(p, v, cover="balls", degree=0)
    assert s.cover.certified is False                      # no simplicialization in R^7
    np.testing.assert_allclose(s(p), v, rtol=1e-13, atol=1e-13)


def test_euclidean_metric_checks_its_dimension():
    with pytest.raises(InvalidParameterError) as exc:
        Euclidean(0)
    assert exc.value.name == "n"
    with pytest.raises(InvalidParameterError, match="last axis must have length 2") as exc:
        Euclidean(2).dist(np.zeros((3, 3)), np.zeros(3))
    assert exc.value.name == "x"


def test_a_polygon_edge_seen_under_no_angle_is_refused_naming_its_point():
    """A 1e-13 edge makes the polygon not star-shaped in rounding (its edge is seen from the
    point under an angle ~0)."""
    polys = [p + SQUARE for p in P2]
    polys[0] = P2[0] + np.array([[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [0.1 - 1e-13, 0.1],
                                 [-0.1, 0.1]])
    with pytest.raises(InvalidPointSetError, match="not star-shaped") as exc:
        GERBSInterpolator(P2, V2, cover=polys, degree=0)
    assert exc.value.indices == (0,)
