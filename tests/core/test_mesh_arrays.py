"""Array helpers of gerbs_core.mesh.arrays."""
import numpy as np
import pytest

from gerbs_core.mesh.arrays import ranges, unique_rows


@pytest.mark.parametrize("dtype", [np.float64, np.int64])
def test_unique_rows_is_numpys_unique_over_rows(dtype):
    """The same groups, numbering and first rows as np.unique(axis=0): numeric
    lexicographic order (negative before positive, -0.0 equal to 0.0), duplicates
    scattered over the input."""
    rng = np.random.default_rng(1)
    a = rng.integers(-3, 4, size=(500, 4)).astype(dtype)
    if dtype is np.float64:
        a *= 0.25
        a[::7, 1] = -0.0 * a[::7, 1]               # signed zeros among the zeros
    _, first, inv = np.unique(a, axis=0, return_index=True, return_inverse=True)
    f2, i2 = unique_rows(a)
    assert np.array_equal(f2, first) and np.array_equal(i2, inv.ravel())
    e1, e2 = unique_rows(np.zeros((0, 3)))
    assert len(e1) == len(e2) == 0


def test_ranges_concatenates_aranges():
    assert ranges([5, 0, 9], [2, 0, 3]).tolist() == [5, 6, 9, 10, 11]
