"""Row sums of the choice's energies (gerbs_core.mesh.row_values): the explicit column
folds must equal numpy's own sums bit for bit (the choice's ties depend on it)."""
import numpy as np
import pytest

from gerbs_core.mesh.row_values import row_sums, square_norms


@pytest.mark.parametrize("n", [1, 2, 3, 4, 7, 8, 13, 32])
def test_row_sums_equal_numpys_sums_bit_for_bit(n):
    rng = np.random.default_rng(n)
    for shape in [(500, n), (20, 6, n)]:
        # magnitudes over ten decades: a different order of the additions would show
        w = rng.normal(size=shape) * 10.0 ** rng.integers(-5, 5, size=shape)
        assert np.array_equal(row_sums(w), w.sum(-1))
        assert np.array_equal(square_norms(w), (w ** 2).sum(-1))
    # a strided view (the Shepard weights' columns, the gaps' components)
    v = rng.normal(size=(300, 2 * n))[:, ::2]
    assert np.array_equal(row_sums(v), v.sum(-1))


def test_a_reordered_sum_would_be_caught():
    # the test's data distinguish the order: (w0 + w1) + w2 != w0 + (w1 + w2) somewhere
    rng = np.random.default_rng(0)
    w = rng.normal(size=(500, 3)) * 10.0 ** rng.integers(-5, 5, size=(500, 3))
    assert not np.array_equal(w[:, 0] + (w[:, 1] + w[:, 2]), row_sums(w))


@pytest.mark.parametrize("n", [1, 2, 3, 7, 8])
def test_row_sums_of_negative_zeros_are_positive_zero_like_numpys(n):
    w = np.full((4, n), -0.0)
    assert np.array_equal(np.signbit(row_sums(w)), np.signbit(w.sum(-1)))
    assert not np.signbit(row_sums(w)).any()
