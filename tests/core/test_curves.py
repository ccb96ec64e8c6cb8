"""GERBS basis (eq. (3)) and curves: Lemma 3 properties and Hermite reproduction."""
import math

import numpy as np
import pytest

from gerbs_core import GERBSBasis, GERBSCurve
from gerbs_core.errors import InvalidParameterError
from gerbs_core.kernels import BFBS, ERBS, Affine, LogisticStep, Step

KNOTS = np.array([-0.4, 0.0, 0.5, 1.3, 2.0, 3.1, 3.5])      # t_0..t_6: n = 5


@pytest.mark.parametrize("kernel", [ERBS(), ERBS(lam=0.3, sigma=2), LogisticStep(),
                                    BFBS(2, 2), Affine(), Step()])
def test_partition_of_unity_nonnegative_and_biorthogonal(kernel):
    B = GERBSBasis(KNOTS, kernel)
    t = np.concatenate([np.linspace(KNOTS[1], KNOTS[-2], 20001), KNOTS[1:-1]])
    G = B(t)
    assert G.shape == (t.size, 5)
    assert np.abs(G.sum(axis=-1) - 1.0).max() <= 1e-15
    assert G.min() >= 0.0 and G.max() <= 1.0
    np.testing.assert_array_equal(B(KNOTS[1:-1]), np.eye(5))           # G_j(t_k) = delta_jk
    # compact supports [t_{j-1}, t_{j+1}]; zero outside [t_0, t_{n+1}]
    for j in range(5):
        lo, hi = B.support(j)
        assert np.all(G[(t <= lo) | (t >= hi), j] == 0.0)
    np.testing.assert_array_equal(B(np.array([-5.0, KNOTS[0], KNOTS[-1], 9.0])), 0.0)


def test_derivatives_of_the_basis_sum_to_zero_and_match_differences():
    B = GERBSBasis(KNOTS)
    t = np.linspace(0.01, 3.09, 777)
    for nu in range(1, 5):
        assert np.abs(B(t, nu).sum(-1)).max() <= 1e-9 * np.abs(B(t, nu)).max()
    h = 1e-6
    fd = (B(t + h) - B(t - h)) / (2 * h)
    np.testing.assert_allclose(B(t, 1), fd, atol=1e-7)


def test_constant_coefficients_trace_the_control_polygon():
    # Lemma 3 (iv): c(t) = sum P_j G_j(t) lies on the segment P_k P_{k+1} for
    # t in [t_k, t_{k+1}], moving monotonically from P_k to P_{k+1}
    rng = np.random.default_rng(5)
    P = rng.normal(size=(5, 3))
    for kernel in (ERBS(), BFBS(1, 3), LogisticStep()):
        c = GERBSCurve(KNOTS, P, kernel)
        for k in range(1, 5):
            t = np.linspace(KNOTS[k], KNOTS[k + 1], 501)
            X = c(t)
            seg = P[k] - P[k - 1]
            u = (X - P[k - 1]) @ seg / (seg @ seg)                  # position along the segment
            off = X - P[k - 1] - u[:, None] * seg                   # distance from the line
            assert np.abs(off).max() <= 1e-14
            assert u[0] == 0.0 and abs(u[-1] - 1.0) <= 1e-15
            assert np.all(np.diff(u) >= -1e-15) and u.min() >= -1e-15 and u.max() <= 1 + 1e-15
        np.testing.assert_array_equal(c(KNOTS[1:-1]), P)
        # and the full closed polygon of Lemma 3: 0 -> P_1 ... P_n -> 0 outside [t_1, t_n]
        np.testing.assert_array_equal(c(np.array([KNOTS[0], KNOTS[-1]])), np.zeros((2, 3)))


def test_taylor_local_curves_reproduce_every_given_derivative():
    rng = np.random.default_rng(11)
    m, d = 4, 2
    L = rng.normal(size=(5, m + 1, d))
    c = GERBSCurve(KNOTS, L)
    for i in range(m + 1):
        np.testing.assert_allclose(c(KNOTS[1:-1], i), L[:, i], rtol=0, atol=1e-12 * 10 ** i)
        np.testing.assert_allclose(c.derivative(i)(KNOTS[1:-1]), L[:, i], rtol=0,
                                   atol=1e-12 * 10 ** i)
    # the curve derivative agrees with finite differences between the knots
    t = np.linspace(0.05, 3.05, 41)
    h = 1e-5
    fd = (c(t + h) - c(t - h)) / (2 * h)
    np.testing.assert_allclose(c(t, 1), fd, atol=1e-6 * np.abs(c(t, 1)).max())
    assert c(np.zeros((3, 4))).shape == (3, 4, d)


def test_hermite_order_is_limited_by_the_kernel_flatness():
    # BFBS(2, 2): F', F'' vanish at 0 and 1, F''' does not -> derivatives up to 2 reproduced
    rng = np.random.default_rng(2)
    L = rng.normal(size=(5, 4, 1))
    c = GERBSCurve(KNOTS, L, BFBS(2, 2))
    for i in range(3):
        np.testing.assert_allclose(c(KNOTS[2:-2], i), L[1:-1, i], atol=1e-10)
    assert np.abs(c(KNOTS[2:-2] + 1e-9, 3) - L[1:-1, 3]).max() > 1e-3
    # Affine reproduces values only
    c = GERBSCurve(KNOTS, L, Affine())
    np.testing.assert_allclose(c(KNOTS[1:-1]), L[:, 0], atol=1e-15)
    assert np.abs(c(KNOTS[2:-2] + 1e-9, 1) - L[1:-1, 1]).max() > 1e-3


def test_per_interval_kernels_bfbs_definition_4():
    i = [1, 2, 3, 1, 2, 1, 1]                         # exponent i_k at knot t_k
    kernels = [BFBS(i[k], i[k + 1]) for k in range(6)]
    B = GERBSBasis(KNOTS, kernels)
    t = np.linspace(KNOTS[1], KNOTS[-2], 3001)
    assert np.abs(B(t).sum(-1) - 1).max() <= 1e-15
    assert B.kernel == tuple(kernels)
    with pytest.raises(InvalidParameterError, match="kernel"):
        GERBSBasis(KNOTS, kernels[:3])


def test_step_kernel_gives_left_continuous_piecewise_constants():
    B = GERBSBasis(KNOTS, Step())
    mid = (KNOTS[2] + KNOTS[3]) / 2                       # jump of G_2 / G_3 here
    G = B(np.array([mid, np.nextafter(mid, 10)]))
    np.testing.assert_array_equal(G[:, 1:3], [[1, 0], [0, 1]])


def test_invalid_knots_and_local_curves_name_the_argument():
    with pytest.raises(InvalidParameterError) as exc:
        GERBSBasis([0.0, 1.0, 1.0, 2.0, 1.5])
    assert exc.value.name == "knots" and exc.value.indices == (2, 4)
    assert "(1, 2)" in str(exc.value) and "(3, 4)" in str(exc.value)
    for bad in ([0.0, 1.0], [[0.0, 1.0, 2.0]], [0.0, np.nan, 2.0]):
        with pytest.raises(InvalidParameterError, match="knots"):
            GERBSBasis(bad)
    with pytest.raises(InvalidParameterError, match="local_curves"):
        GERBSCurve(KNOTS, np.zeros((4, 2)))
    with pytest.raises(InvalidParameterError, match="local_curves"):
        GERBSCurve(KNOTS, np.zeros(5))
    with pytest.raises(InvalidParameterError, match="local_curves"):
        GERBSCurve(KNOTS, np.full((5, 2), np.inf))
    with pytest.raises(InvalidParameterError, match="kernel"):
        GERBSBasis(KNOTS, "bogus")
    with pytest.raises(InvalidParameterError, match="nu"):
        GERBSBasis(KNOTS)(0.5, 99)


def test_nan_and_no_mutation():
    knots = KNOTS.copy()
    P = np.arange(10.0).reshape(5, 2)
    P0 = P.copy()
    c = GERBSCurve(knots, P)
    t = np.array([0.2, np.nan])
    out = c(t)
    assert np.isnan(out[1]).all() and np.isfinite(out[0]).all()
    assert np.isnan(GERBSBasis(knots)(t)[1]).all()
    np.testing.assert_array_equal(P, P0)
    np.testing.assert_array_equal(knots, KNOTS)
    P[0] = 99.0                                           # the curve keeps its own copy
    assert c(KNOTS[1])[0] == 0.0
    assert math.isclose(GERBSBasis(knots).domain[1], 3.1)
