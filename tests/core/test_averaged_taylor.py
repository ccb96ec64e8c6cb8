"""Averaged (regularized) Taylor coefficients of Lemma 5 (gerbs_core.scattered.taylor.
averaged_taylor) away from the plane: the masked tensor Gauss rule of n != 2.

Q f(x) averages the degree-m Taylor polynomials of f at the points y of the ball B(x_i, r):
it reproduces polynomials of degree <= m, and for f = |y|^2 its value at the centre is
|c|^2 + 3/5 r^2 (m = 0, the ball mean) or |c|^2 - 3/5 r^2 (m = 1) in R^3.
"""
import numpy as np
import pytest

from gerbs_core import GERBSInterpolator
from gerbs_core.errors import InvalidParameterError
from gerbs_core.scattered.taylor import averaged_taylor


def _square_jet(y):
    """f = |y|^2 (one value): [f (..., 1), grad (..., 1, n), Hess (..., 1, n, n)]."""
    n = y.shape[-1]
    return [(y ** 2).sum(-1)[..., None], 2.0 * y[..., None, :],
            np.broadcast_to(2.0 * np.eye(n), y.shape[:-1] + (1, n, n))]


def _cubic_jet(y):
    """f = y_0^3 (one value)."""
    n = y.shape[-1]
    g = np.zeros(y.shape[:-1] + (1, n))
    g[..., 0, 0] = 3 * y[..., 0] ** 2
    h = np.zeros(y.shape[:-1] + (1, n, n))
    h[..., 0, 0, 0] = 6 * y[..., 0]
    return [y[..., :1] ** 3, g, h]


C = np.array([[0.3, -0.2, 0.5], [1.0, 2.0, 3.0], [-0.7, 0.0, 0.1]])
R = np.array([0.4, 0.1, 0.25])


@pytest.mark.parametrize("n", [1, 3])
def test_degree_two_reproduces_a_quadratic(n):
    c, r = C[:, :n], R
    v, g, h = averaged_taylor(_square_jet, c, r, 2)
    np.testing.assert_allclose(v[:, 0], (c ** 2).sum(1), rtol=1e-13)
    np.testing.assert_allclose(g[:, 0], 2 * c, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(h[:, 0], np.broadcast_to(2 * np.eye(n), (3, n, n)), rtol=1e-13)


def test_low_degrees_average_over_the_ball_in_3d():
    exact0 = (C ** 2).sum(1) + 0.6 * R ** 2
    errs = []
    for n_quad in (8, 16):
        v, = averaged_taylor(_square_jet, C, R, 0, n_quad=n_quad)
        errs.append(np.abs(v[:, 0] - exact0) / R ** 2)
    assert errs[0].max() <= 0.06 and errs[1].max() <= 0.015     # the masked cube -> the ball
    assert errs[1].max() < errs[0].max()
    v, g = averaged_taylor(_square_jet, C, R, 1, n_quad=16)
    np.testing.assert_allclose(v[:, 0], (C ** 2).sum(1) - 0.6 * R ** 2, atol=0.015 * R.max() ** 2)
    np.testing.assert_allclose(g[:, 0], 2 * C, rtol=1e-12, atol=1e-14)  # symmetric rule: mean of y


def test_degree_above_two_is_refused():
    with pytest.raises(InvalidParameterError) as exc:
        averaged_taylor(_square_jet, C, R, 3)
    assert exc.value.name == "degree"


def test_regularized_interpolant_in_3d_reproduces_a_quadratic():
    rng = np.random.default_rng(0)
    pts = rng.uniform(0.0, 1.0, (40, 3))
    x = rng.uniform(0.3, 0.7, (20, 3))
    interp = GERBSInterpolator(pts, (pts ** 2).sum(1), degree=2, regularized=_square_jet)
    assert np.abs(interp(x) - (x ** 2).sum(1)).max() <= 1e-12
    # the check sees a function of higher degree than the local functions reproduce
    cubic = GERBSInterpolator(pts, pts[:, 0] ** 3, degree=2, regularized=_cubic_jet)
    assert np.abs(cubic(x) - x[:, 0] ** 3).max() > 1e-6
