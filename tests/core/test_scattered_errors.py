"""Bad input to the scattered-point interpolator: specific errors naming the problem
and the offending indices; the caller's arrays are never modified."""
import numpy as np
import pytest

from gerbs_core import GERBSInterpolator
from gerbs_core.errors import InvalidParameterError, InvalidPointSetError

RNG = np.random.default_rng(99)


def data(N=20, n=2):
    P = RNG.random((N, n))
    return P, np.sin(P.sum(1))


def test_duplicate_points():
    P, v = data()
    P[11] = P[4]
    with pytest.raises(InvalidPointSetError, match="duplicate") as ei:
        GERBSInterpolator(P, v)
    assert set(ei.value.indices) == {4, 11}


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_points_and_values(bad):
    P, v = data()
    P2 = P.copy()
    P2[3, 0] = bad
    with pytest.raises(InvalidPointSetError, match="non-finite") as ei:
        GERBSInterpolator(P2, v)
    assert ei.value.indices == (3,)
    v2 = v.copy()
    v2[[5, 8]] = bad
    with pytest.raises(InvalidPointSetError, match="values") as ei:
        GERBSInterpolator(P, v2)
    assert ei.value.indices == (5, 8)
    g = np.zeros((len(P), 2))
    g[2, 1] = bad
    with pytest.raises(InvalidPointSetError, match="gradients") as ei:
        GERBSInterpolator(P, v, g)
    assert ei.value.indices == (2,)


def test_too_few_points():
    with pytest.raises(InvalidPointSetError, match=">= 3 points"):
        GERBSInterpolator(RNG.random((2, 2)), np.zeros(2), cover="delaunay")
    # values only with degree 3 in the plane needs 10 points (9 unknowns + itself)
    P, v = data(6)
    with pytest.raises(InvalidPointSetError, match="too few"):
        GERBSInterpolator(P, v, degree=3)
    GERBSInterpolator(P, v, degree=1)                   # fine with fewer unknowns


def test_collinear_points_for_delaunay():
    t = np.linspace(0, 1, 10)
    P = np.stack([t, 2 * t + 1], -1)
    with pytest.raises(InvalidPointSetError, match="collinear"):
        GERBSInterpolator(P, t, degree=0, cover="delaunay")
    # the ball cover handles them (R from nearest neighbours)
    interp = GERBSInterpolator(P, t, np.tile([[0.2, 0.4]], (10, 1)), degree=1, cover="balls")
    np.testing.assert_allclose(interp(P), t, atol=1e-14)


def test_points_outside_the_voronoi_domain():
    P, v = data()
    dom = np.array([[0.1, 0.1], [0.9, 0.1], [0.9, 0.9], [0.1, 0.9]])
    out = np.flatnonzero(np.any((P <= 0.1) | (P >= 0.9), axis=1))
    assert out.size
    with pytest.raises(InvalidPointSetError, match="outside") as ei:
        GERBSInterpolator(P, v, cover="voronoi", domain=dom)
    assert ei.value.indices == tuple(out)
    with pytest.raises(InvalidParameterError, match="convex"):
        GERBSInterpolator(P, v, cover="voronoi", domain=dom[::-1])


def test_mismatched_shapes():
    P, v = data()
    with pytest.raises(InvalidParameterError, match="values"):
        GERBSInterpolator(P, v[:-1])
    with pytest.raises(InvalidParameterError, match="gradients"):
        GERBSInterpolator(P, v, np.zeros((len(P), 3)))
    with pytest.raises(InvalidParameterError, match="hessians"):
        GERBSInterpolator(P, v, np.zeros((len(P), 2)), np.zeros((len(P), 2)))
    with pytest.raises(InvalidParameterError, match="hessians"):
        GERBSInterpolator(P, v, None, np.zeros((len(P), 2, 2)))
    interp = GERBSInterpolator(P, v)
    with pytest.raises(InvalidParameterError, match="x"):
        interp(np.zeros((4, 3)))
    with pytest.raises(InvalidParameterError, match="nu"):
        interp(P, nu=3)
    with pytest.raises(InvalidParameterError, match="cover"):
        GERBSInterpolator(RNG.random((20, 3)), v, cover="voronoi")
    with pytest.raises(InvalidParameterError, match="cover"):
        GERBSInterpolator(RNG.random((20, 1)), v, cover="delaunay")
    with pytest.raises(InvalidParameterError, match="degree"):
        GERBSInterpolator(P, v, degree=4)


def test_radii_violating_the_constraints():
    P, v = data(30, 3)
    g = np.zeros((30, 3))
    d = np.linalg.norm(P[:, None] - P[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    rho = 0.4 * d.min(1)
    rho[[2, 17]] = 1.2 * d.min(1)[[2, 17]]
    with pytest.raises(InvalidParameterError, match=r"\(16\).*\[2, 17\]"):
        GERBSInterpolator(P, v, g, cover="balls", rho=rho, R=1.0, degree=1)
    with pytest.raises(InvalidParameterError, match=r"\(17\)"):
        GERBSInterpolator(P, v, g, cover="balls", rho=0.4 * d.min(1), R=0.1 * d.min(1), degree=1)
    with pytest.raises(InvalidParameterError, match="> 0"):
        GERBSInterpolator(P, v, g, cover="balls", R=-1.0, degree=1)


def test_caller_arrays_not_modified():
    P, v = data()
    g = np.cos(P)
    H = np.zeros((len(P), 2, 2))
    H[:, 0, 1] = 1.0                      # asymmetric on purpose: symmetrized internally
    copies = [a.copy() for a in (P, v, g, H)]
    interp = GERBSInterpolator(P, v, g, H)
    x = RNG.random((10, 2))
    xc = x.copy()
    interp(x, nu=2)
    for a, c in zip((P, v, g, H, x), copies + [xc]):
        np.testing.assert_array_equal(a, c)


@pytest.mark.parametrize("nu, text", [(1.0, "integer, got 1.0"), (np.float64(1), "integer"),
                                      (True, "integer, got True"), (3, "max_order = 2"),
                                      (-1, ">= 0")])
def test_derivative_order_is_an_integer_named_nu(nu, text):
    """Found by a review: nu=1.0 crashed inside the evaluation with a raw TypeError
    ("can't multiply sequence by non-int"), nu=True was blamed on ``nmax``."""
    P, v = data()
    interp = GERBSInterpolator(P, v)
    with pytest.raises(InvalidParameterError, match=text) as ei:
        interp(P[:2], nu=nu)
    assert ei.value.name == "nu"
    assert interp(P[:2], nu=np.int64(1)).shape == (2, 2)


@pytest.mark.parametrize("chunk", [1.5, 0, True, "8"])
def test_chunk_size_is_a_positive_integer(chunk):
    P, v = data()
    with pytest.raises(InvalidParameterError, match="integer >= 1") as ei:
        GERBSInterpolator(P, v, chunk_size=chunk)
    assert ei.value.name == "chunk_size"


def test_interpolators_are_immutable_and_their_points_read_only():
    """A review set ``I.degree = 0``: the interpolant changed by 0.028 while the object's
    data said nothing had; ``I.points`` was a writable array the evaluation ignored. Now
    both refuse, and the caller's array stays writable (the interpolator keeps a copy)."""
    P, v = data()
    interp = GERBSInterpolator(P, v)
    before = interp(P[:3] * 0.9 + 0.05)
    for attr in ("degree", "kernel", "points", "new_name"):
        with pytest.raises(AttributeError, match="immutable"):
            setattr(interp, attr, 0)
    with pytest.raises(ValueError):
        interp.points[0, 0] = 0.5
    assert P.flags.writeable
    assert np.array_equal(interp(P[:3] * 0.9 + 0.05), before)
    interp(P[:3], nu=2)             # the lazy tables of the derivatives still fill


def test_one_dimensional_queries_may_omit_the_last_axis():
    """In R^1 the points may be given as (N,); the queries now too, as interp1d's: (M,)
    queries give (M,) values, the same as (M, 1)."""
    x = np.linspace(0.0, 1.0, 12)
    interp = GERBSInterpolator(x, np.cos(3 * x))
    q = np.array([0.13, 0.5, 0.77])
    assert interp(q).shape == (3,)
    assert np.array_equal(interp(q), interp(q[:, None]))
    assert np.abs(interp(x) - np.cos(3 * x)).max() <= 1e-12
    assert interp(0.5).shape == () and interp(np.array([0.5])).shape == (1,)
