"""LogisticStep, Affine, Step and CustomCDF kernels (Definitions 2-3, section 2.1.3)."""
import math

import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError
from gerbs_core.kernels import BFBS, ERBS, Affine, CustomCDF, Kernel, LogisticStep, Step

from .ids import kernel_id


def _cauchy(f, x, m, nodes=128):
    """f^(m)(x) by the Cauchy integral on |z - x| = min(x, 1-x)/2 (f analytic there)."""
    r = min(x, 1.0 - x) / 2.0
    dz = r * np.exp(2j * np.pi * np.arange(nodes) / nodes)
    with np.errstate(over="ignore"):
        vals = f(x + dz)
    return (math.factorial(m) * np.mean(vals * dz ** (-m))).real


def test_logistic_values_are_the_closed_form():
    k = LogisticStep()
    x = np.linspace(0.001, 0.999, 999)
    with np.errstate(over="ignore"):
        ref = 1.0 / (1.0 + np.exp(1.0 / x - 1.0 / (1.0 - x)))
    assert np.abs(k.cdf(x) - ref).max() <= 3e-16
    np.testing.assert_array_equal(k.cdf(np.array([-1.0, 0.0, 1.0, 3.0, np.inf])), [0, 0, 1, 1, 1])
    assert np.abs(k.cdf(x) + k.cdf(1 - x) - 1).max() <= 3e-16       # F(1-t) = 1 - F(t)
    assert isinstance(k, Kernel) and k.smoothness == math.inf and k.max_order >= 4


def test_logistic_derivatives_match_cauchy_integrals():
    k = LogisticStep()
    # F and 1 - F, each evaluated where it is small (relative accuracy): the
    # Cauchy sum's rounding error is ~eps * max|f| * m! / r^m
    f = lambda z: 1.0 / (1.0 + np.exp(1.0 / z - 1.0 / (1.0 - z)))  # noqa: E731
    g = lambda z: 1.0 / (1.0 + np.exp(1.0 / (1.0 - z) - 1.0 / z))  # noqa: E731
    x = np.linspace(0.05, 0.95, 37)
    D = k.cdf_derivs(x, 6)
    for m in range(1, 7):
        ref = np.array([_cauchy(f, xi, m) if xi <= 0.5 else -_cauchy(g, xi, m) for xi in x])
        assert np.abs(D[m] - ref).max() <= 1e-12 * np.abs(ref).max(), m
        np.testing.assert_array_equal(k.cdf(x, m), D[m])


def test_logistic_is_flat_at_the_ends():
    k = LogisticStep()
    x = np.array([0.0, 1e-300, 1e-6, 1e-3, 1 - 1e-3, 1 - 1e-6, 1.0])
    assert np.abs(k.cdf_derivs(x, 8)[1:]).max() <= 1e-12
    assert np.isnan(k.cdf_derivs(np.array([np.nan]), 4)).all()


def test_affine_is_the_hat_and_is_only_c0():
    k = Affine()
    x = np.array([-1.0, 0.0, 0.25, 0.5, 1.0, 2.0, np.nan])
    np.testing.assert_array_equal(k.cdf(x)[:-1], [0, 0, 0.25, 0.5, 1, 1])
    np.testing.assert_array_equal(k.cdf(x, 1)[:-1], [0, 0, 1, 1, 0, 0])
    assert np.isnan(k.cdf(x, 2)[-1]) and np.isnan(k.cdf(x)[-1])
    np.testing.assert_array_equal(k.bump(np.array([-0.5, 0.0, 0.5, 1.5])), [0.5, 1, 0.5, 0])
    assert k.smoothness == 0


def test_step_is_left_continuous():
    k = Step()
    x = np.array([-1.0, 0.0, 0.25, 0.5, 0.5 + 1e-16 * 0 + np.spacing(0.5), 0.75, 1.0, 2.0])
    np.testing.assert_array_equal(k.cdf(x), [0, 0, 0, 0, 1, 1, 1, 1])   # F(1/2) = F(1/2-) = 0
    np.testing.assert_array_equal(k.cdf(x, 1), np.zeros(8))
    assert Step(at=0.0).cdf(1e-300) == 1.0 and Step(at=0.0).cdf(0.0) == 0.0
    assert k.smoothness == -1
    for bad in (1.0, -0.1, float("nan"), "x"):
        with pytest.raises(InvalidParameterError, match="at"):
            Step(at=bad)


def test_custom_cdf_wraps_a_user_function_with_derivatives():
    k = CustomCDF(lambda x: x ** 3, [lambda x: 3 * x ** 2, lambda x: 6 * x], smoothness=0)
    x = np.array([-1.0, 0.5, 2.0, np.nan])
    np.testing.assert_array_equal(k.cdf(x)[:3], [0, 0.125, 1])
    np.testing.assert_array_equal(k.cdf(x, 2)[:3], [0, 3.0, 0])
    assert np.isnan(k.cdf(x, 1)[3])
    assert k.max_order == 2
    with pytest.raises(InvalidParameterError, match="nu"):
        k.cdf(0.5, 3)


@pytest.mark.parametrize("f, match", [
    (lambda x: np.sin(3 * x) / np.sin(3), "monotone"),
    (lambda x: 0.5 + 0.5 * x, "F\\(0\\)"),
    (lambda x: 0.9 * x, "F\\(1\\)"),
    (lambda x: np.where(x == 0.5, np.nan, x), "non-finite"),
    (lambda x: 0.5, "vectorized"),
    (3.0, "callable"),
])
def test_custom_cdf_validation_names_f(f, match):
    with pytest.raises(InvalidParameterError, match=match) as exc:
        CustomCDF(f)
    assert exc.value.name == "f"


def test_custom_cdf_validates_derivatives_and_options():
    with pytest.raises(InvalidParameterError) as exc:
        CustomCDF(lambda x: x, [None])
    assert exc.value.name == "derivatives"
    with pytest.raises(InvalidParameterError) as exc:
        CustomCDF(lambda x: x, smoothness=-5)
    assert exc.value.name == "smoothness"
    with pytest.raises(InvalidParameterError) as exc:
        CustomCDF(lambda x: x, n_check=2)
    assert exc.value.name == "n_check"


ALL_KERNELS = [ERBS(), ERBS(lam=0.0), ERBS(0.5, 2, 1.5, 0.4, 2), BFBS(2, 2), BFBS(1.5, 2),
               LogisticStep(), Affine(), Step(), CustomCDF(lambda x: x * x, [lambda x: 2 * x])]


@pytest.mark.parametrize("k", ALL_KERNELS, ids=kernel_id)
def test_contract_scalars_shapes_nan_for_every_kernel(k):
    n = min(2, k.max_order)
    t = np.array([[0.3, np.nan, 1.5], [0.0, -2.0, 0.7]])
    D = k.cdf_derivs(t, n)
    B = k.bump_derivs(t, n)
    assert D.shape == B.shape == (n + 1, 2, 3)
    assert np.isnan(D[:, 0, 1]).all() and np.isnan(B[:, 0, 1]).all()
    for m in range(n + 1):
        np.testing.assert_array_equal(k.cdf(t, m), D[m])
        np.testing.assert_array_equal(k.bump(t, m), B[m])
        for i, j in ((0, 0), (0, 2), (1, 0), (1, 1), (1, 2)):
            v = k.cdf(t[i, j], m)                      # python float in: 0-d out
            assert np.ndim(v) == 0 and v == D[m, i, j]
            assert np.ndim(k.bump(t[i, j], m)) == 0
        assert np.array_equal(k.cdf_derivs(float(t[0, 0]), n), D[:, 0, 0])
    np.testing.assert_array_equal(D[0][[0, 1, 1], [2, 0, 1]], [1.0, 0.0, 0.0])
    np.testing.assert_array_equal(D[1:][:, [0, 1, 1], [2, 0, 1]], 0.0)   # outside (0, 1)
