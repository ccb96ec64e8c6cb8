"""The one GERBS spline evaluator (splines.evaluate): the Leibniz rule of eq. (3)'s
transition and exact interpolation at the interval ends."""
import numpy as np

from gerbs_core.kernels import BFBS, ERBS
from gerbs_core.splines.evaluate import blend_jet, knot_interval, rising_jet, spline_jet


def _poly_jet(c, t, nu):
    """Jets (nu+1, P) of the polynomial sum_k c[k] t^k."""
    p = np.polynomial.Polynomial(c)
    return np.array([p.deriv(i)(t) if i else p(t) for i in range(nu + 1)])


def test_derivatives_match_finite_differences_of_the_values():
    # s = (1 - F((t - t0)/h)) l0 + F(.) l1 on [t0, t0 + h]; derivatives by the Leibniz rule
    t0, h, nu = 0.3, 0.07, 3          # a short interval: the h^-i factors matter
    t = t0 + h * np.linspace(0.05, 0.95, 41)
    c0, c1 = [1.0, -2.0, 0.5, 3.0], [0.2, 1.0, -4.0, 0.7]
    for kernel in (ERBS(), BFBS(2, 3)):
        jet = spline_jet(kernel, (t - t0) / h, h, _poly_jet(c0, t, nu), _poly_jet(c1, t, nu), nu)

        def value(x):
            return spline_jet(kernel, (x - t0) / h, h, _poly_jet(c0, x, 0), _poly_jet(c1, x, 0), 0)[0]

        d = 1e-5 * h
        for i in range(1, nu + 1):
            lower = spline_jet(kernel, (t - d - t0) / h, h, _poly_jet(c0, t - d, nu),
                               _poly_jet(c1, t - d, nu), nu)[i - 1]
            upper = spline_jet(kernel, (t + d - t0) / h, h, _poly_jet(c0, t + d, nu),
                               _poly_jet(c1, t + d, nu), nu)[i - 1]
            fd = (upper - lower) / (2 * d)
            scale = np.abs(jet[i]).max()
            assert np.abs(fd - jet[i]).max() <= 1e-6 * scale, (kernel, i)
        np.testing.assert_array_equal(jet[0], value(t))       # order 0 independent of nu


def test_the_ends_of_the_interval_are_the_local_functions_to_the_last_bit():
    # Hermite interpolation at the knots (Lemma 3 (ii)): where F = 0 the spline is l0, where
    # F = 1 it is l1, every order (ERBS is flat at both ends), bit for bit
    rng = np.random.default_rng(2)
    left, right = rng.normal(size=(4, 200)) * 1e3, rng.normal(size=(4, 200)) * 1e3
    for w, want in ((0.0, left), (1.0, right)):
        rise = rising_jet(ERBS(), np.full(200, w), 0.01, 3)
        np.testing.assert_array_equal(blend_jet(left, right, rise, 3), want)
    # control: the difference form l0 + F (l1 - l0) misses l1 at F = 1 by rounding
    assert not np.array_equal(left[0] + 1.0 * (right[0] - left[0]), right[0])


def test_rising_jet_is_the_chain_rule_and_vector_local_functions_broadcast():
    w, h = np.array([0.2, 0.5, 0.9]), np.array([0.5, 2.0, 0.1])
    F = ERBS().cdf_derivs(w, 2)
    rise = rising_jet(ERBS(), w, h, 2)
    np.testing.assert_allclose(rise, F / h ** np.arange(3)[:, None], rtol=1e-15)
    assert rising_jet(ERBS(), 0.5, 1.0, 1).shape == (2,)          # 0-d input
    left, right = np.zeros((3, 3, 2)), np.ones((3, 3, 2))
    right[1:] = 0.0                                                 # constants 0 -> 1
    out = blend_jet(left, right, rise[..., None], 2)
    np.testing.assert_allclose(out, np.broadcast_to(rise[..., None], (3, 3, 2)), rtol=1e-15)


def test_knot_interval_sides():
    knots = np.array([0.0, 1.0, 2.0])
    t = np.array([-1.0, 0.0, 0.5, 1.0, 2.0, 3.0])
    assert knot_interval(knots, t, side="left").tolist() == [-1, -1, 0, 0, 1, 2]
    assert knot_interval(knots, t, side="right").tolist() == [-1, 0, 0, 1, 2, 2]
