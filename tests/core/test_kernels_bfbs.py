"""BFBS kernel (Definition 4, eqs. (4)-(7)): closed forms and smoothness at the knots."""
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import betainc

from gerbs_core.splines.curves import GERBSBasis
from gerbs_core.errors import InvalidParameterError
from gerbs_core.kernels import BFBS, ERBS, Affine, LogisticStep

pytestmark = pytest.mark.filterwarnings("ignore::scipy.integrate.IntegrationWarning")


@pytest.mark.parametrize("il, ir", [(0, 0), (1, 1), (2, 3), (4, 1), (5, 5)])
def test_bernstein_form_equals_incomplete_beta(il, ir):
    k = BFBS(il, ir)
    x = np.linspace(0.0, 1.0, 1001)
    F = k.cdf(x)
    assert np.abs(F - k.bernstein_cdf(x)).max() <= 1e-14
    assert np.abs(F - betainc(il + 1, ir + 1, x)).max() <= 1e-14
    # eq. (6) density, normalized by (5), integrated independently
    psi = lambda s: s ** il * (1 - s) ** ir  # noqa: E731
    S = 1.0 / quad(psi, 0, 1, epsabs=1e-16, epsrel=1e-15)[0]
    for xi in (0.2, 0.5, 0.9):
        ref = S * quad(psi, 0, xi, epsabs=1e-16)[0]
        assert F[int(round(xi * 1000))] == pytest.approx(ref, abs=1e-14)


def test_derivatives_are_the_closed_form_density_and_its_derivatives():
    k = BFBS(2, 3)
    x = np.linspace(0.01, 0.99, 50)
    D = k.cdf_derivs(x, 5)
    c = 1.0 / math.gamma(3) / math.gamma(4) * math.gamma(7)        # 1 / B(3, 4) = 60
    poly = np.polynomial.Polynomial([0, 0, 1]) * np.polynomial.Polynomial([1, -1]) ** 3 * c
    for m in range(1, 6):
        np.testing.assert_allclose(D[m], poly.deriv(m - 1)(x), rtol=1e-13, atol=1e-12)
    # non-integer exponents: F' against a central difference of F
    k = BFBS(1.5, 0.5)
    h = 1e-6
    np.testing.assert_allclose(k.cdf(x, 1), (k.cdf(x + h) - k.cdf(x - h)) / (2 * h), rtol=1e-7)


def _knot_jumps(kernel, nmax, delta):
    """|G^(m)(t_1 + delta) - G^(m)(t_1 - delta)|, m = 0..nmax, at the middle knot of
    a GERBS basis on knots (0, 1, 3) (unequal spacing: h = 1 left, 2 right)."""
    B = GERBSBasis([0.0, 1.0, 3.0], kernel)
    t = np.array([1.0 - delta, 1.0 + delta])
    return np.array([abs(np.diff(B(t, m)[:, 0])[0]) for m in range(nmax + 1)])


@pytest.mark.parametrize("i", [0, 1, 2, 3])
def test_smoothness_order_at_the_knots_integer(i):
    # derived: F ~ A t^(i+1) / (i+1)! at 0 with A = F^(i+1)(0+) = i! / B(i+1, i+1),
    # so F is C^i on R and F^(i+1) jumps from 0 to A at 0 (and, by symmetry,
    # F^(i+1)(1-) = (-1)^i A at 1).
    k = BFBS(i, i)
    assert k.smoothness == i
    A = math.factorial(i) * math.exp(math.lgamma(2 * i + 2) - 2 * math.lgamma(i + 1))
    d = k.cdf_derivs(np.array([1e-9, 1e-10, 1 - 1e-10]), i + 1)
    assert d[i + 1, 1] == pytest.approx(A, rel=1e-6)
    assert d[i + 1, 2] == pytest.approx((-1) ** i * A, rel=1e-6)
    assert k.cdf(-1e-10, i + 1) == 0.0                 # the left limit: a jump of A
    for m in range(1, i + 1):                          # lower orders: one-sided limit 0
        assert abs(d[m, 1]) <= 0.2 * abs(d[m, 0]) + 1e-300
    # in the GERBS basis (eq. (3)) at a knot: orders <= i continuous (jump -> 0
    # linearly or faster with delta), order i+1 jumps by |(-1)^i A + A / 2^(i+1)|
    J1, J2 = _knot_jumps(k, i + 1, 1e-5), _knot_jumps(k, i + 1, 1e-6)
    assert np.all(J2[: i + 1] <= 0.2 * J1[: i + 1] + 1e-15), (J1, J2)
    expected = abs((-1) ** i * A + A / 2 ** (i + 1))
    assert J2[i + 1] == pytest.approx(expected, rel=1e-4)


def test_smoothness_order_non_integer_and_mixed():
    assert BFBS(1.5, 3).smoothness == 2          # F ~ t^2.5: F'' -> 0 continuous, F''' unbounded
    assert BFBS(3, 0.25).smoothness == 1
    k = BFBS(1.5, 1.5)
    small = k.cdf_derivs(np.array([1e-8, 1e-10]), 3)
    assert small[2, 1] == pytest.approx(0.1 * small[2, 0], rel=1e-3)   # F'' ~ t^0.5 -> 0
    assert small[3, 1] == pytest.approx(10 * small[3, 0], rel=1e-3)    # F''' ~ t^-0.5 -> inf


def test_smooth_kernels_show_no_jump_and_the_check_catches_a_kink():
    for k in (ERBS(), LogisticStep()):
        assert np.all(_knot_jumps(k, 4, 1e-4) <= 1e-12)
    # deliberately kinked variant: the affine hat jumps in the first derivative
    # (slope 1 on the left interval of length 1, -1/2 on the right one of length 2)
    J = _knot_jumps(Affine(), 2, 1e-4)
    assert J[0] <= 1e-3 and J[1] == pytest.approx(1.5, abs=1e-12)


def test_invalid_exponents_and_bernstein_needs_integers():
    for kw, name in (({"i_left": -1}, "i_left"), ({"i_right": float("inf")}, "i_right"),
                     ({"i_left": "2"}, "i_left")):
        with pytest.raises(InvalidParameterError) as exc:
            BFBS(**kw)
        assert exc.value.name == name
    with pytest.raises(InvalidParameterError, match="integer"):
        BFBS(1.5, 2).bernstein_cdf(0.3)
    k = BFBS(2, 2)
    t = np.array([np.nan, -1.0, 2.0])
    out = k.cdf(t)
    assert np.isnan(out[0]) and out[1] == 0 and out[2] == 1
    assert np.isnan(k.cdf(t, 3)[0])


@pytest.mark.parametrize("il,ir", [(40, 40), (50, 50), (200, 3), (500, 500)])
def test_large_integer_exponents_evaluate_like_betainc(il, ir):
    """Binomials above 2**63 used to turn the Bernstein sum into an object array
    (UFuncTypeError from (40, 40) on); up to MAX_EXPONENT the form stays accurate."""
    t = np.linspace(0.0, 1.0, 401)
    k = BFBS(il, ir)
    assert np.abs(k(t) - betainc(il + 1.0, ir + 1.0, t)).max() <= 1e-12
    assert all(np.all(np.isfinite(k(t, nu))) for nu in range(k.max_order + 1))


@pytest.mark.parametrize("kw,name", [({"i_left": 501}, "i_left"), ({"i_right": 1e6}, "i_right"),
                                     ({"i_left": 600, "i_right": 600}, "i_left")])
def test_exponents_above_the_maximum_are_named(kw, name):
    from gerbs_core.kernels.bfbs import MAX_EXPONENT

    with pytest.raises(InvalidParameterError, match=f"{name}: .*\\[0, {MAX_EXPONENT}\\]") as exc:
        BFBS(**kw)
    assert exc.value.name == name
