"""Franke's six functions: known values and exact derivatives."""
import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError
from gerbs_core.datasets.franke import franke

RNG = np.random.default_rng(5)


def test_known_values():
    c = np.array([0.5, 0.5])
    assert franke(4, c) == pytest.approx(1 / 3, rel=1e-15)
    assert franke(5, c) == pytest.approx(1 / 3, rel=1e-15)
    assert franke(6, c) == pytest.approx(8 / 9 - 0.5, rel=1e-15)
    assert franke(2, np.array([0.3, 0.3])) == pytest.approx(1 / 9, rel=1e-15)
    assert franke(3, np.array([1 / 3, 0.0])) == pytest.approx(2.25 / 6, rel=1e-15)
    # F1 at (2/9, 2/9): first bump at its peak plus the tails of the others
    p = np.array([2 / 9, 2 / 9])
    ref = (0.75 + 0.75 * np.exp(-9 / 49 - 0.3) + 0.5 * np.exp(-(25 + 1) / 4) - 0.2 * np.exp(-4 - 25))
    assert franke(1, p) == pytest.approx(ref, rel=1e-14)


@pytest.mark.parametrize("k", range(1, 7))
def test_derivatives_match_finite_differences(k):
    p = 0.1 + 0.8 * RNG.random((50, 2))
    h = 1e-5
    g, H = franke(k, p, 1), franke(k, p, 2)
    assert g.shape == (50, 2) and H.shape == (50, 2, 2)
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2), rtol=0, atol=0)
    for j in range(2):
        e = np.zeros(2)
        e[j] = h
        fd = (franke(k, p + e) - franke(k, p - e)) / (2 * h)
        fdg = (franke(k, p + e, 1) - franke(k, p - e, 1)) / (2 * h)
        assert np.max(np.abs(fd - g[:, j])) <= 1e-7 * max(1, np.abs(g).max())
        assert np.max(np.abs(fdg - H[:, :, j])) <= 1e-6 * max(1, np.abs(H).max())


def test_bad_arguments():
    with pytest.raises(InvalidParameterError, match="k"):
        franke(7, np.zeros(2))
    with pytest.raises(InvalidParameterError, match="p"):
        franke(1, np.zeros(3))
    with pytest.raises(InvalidParameterError, match="nu"):
        franke(1, np.zeros(2), nu=3)
