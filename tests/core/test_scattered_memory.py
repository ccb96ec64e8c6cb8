"""The scattered interpolator's evaluation in bounded memory: a budget refused before
anything is allocated (ResourceLimitError naming memory_budget and stating the
estimate), an estimate that bounds the measured peak, chunked results identical to
one-block results, and working memory that does not grow with the number of queries."""
import re
import tracemalloc

import numpy as np
import pytest

from gerbs_core import GERBSInterpolator
from gerbs_core.errors import ResourceLimitError

RNG = np.random.default_rng(77)


def _peak(fn):
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = fn()
        return out, tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()


def test_refused_before_allocating_with_the_estimate():
    P = RNG.random((300, 3))
    interp = GERBSInterpolator(P, np.sin(P.sum(1)), memory_budget=20e6)
    X = RNG.random((2_000_000, 3)) * 0.5 + 0.25          # output alone: 16 MB + ordering
    with pytest.raises(ResourceLimitError, match="memory_budget") as info:
        _, peak = _peak(lambda: interp(X))
    num, unit = re.search(r"estimated memory ([\d.]+) (GB|MB|kB)", str(info.value)).groups()
    est = float(num) * {"GB": 1e9, "MB": 1e6, "kB": 1e3}[unit]
    assert est > 20e6
    tracemalloc.start()
    try:
        with pytest.raises(ResourceLimitError):
            interp(X, nu=1)
        assert tracemalloc.get_traced_memory()[1] < 1e6     # nothing of the size was allocated
    finally:
        tracemalloc.stop()
    assert interp.memory_estimate(len(X), 1) > interp.memory_estimate(len(X), 0)


@pytest.mark.parametrize("n,cover", [(2, "delaunay"), (2, "balls"), (3, "delaunay"), (3, "balls"),
                                     (4, "delaunay")])
def test_estimate_bounds_the_measured_peak(n, cover):
    """tracemalloc peak <= estimate for 50,000 / 12,000 / 4,000 queries (n = 2, 3, 4), nu = 0, 1, 2,
    with a budget small enough that the evaluation runs in many chunks (work 10 MB / 5 MB);
    and the estimate is not a wild bound (peak >= estimate / 8)."""
    P = RNG.random((1500 if n < 4 else 600, n))
    interp = GERBSInterpolator(P, np.sin(P.sum(1)), cover=cover, memory_budget=40e6 if n == 2 else 20e6)
    X = RNG.random(({2: 50_000, 3: 12_000, 4: 4_000}[n], n)) * 0.8 + 0.1
    for nu in (0, 1, 2):
        est = interp.memory_estimate(len(X), nu)
        out, peak = _peak(lambda: interp(X, nu))
        assert out.shape == (len(X),) + (n,) * nu and np.isfinite(out).mean() > 0.95   # hull
        assert peak <= est, (nu, peak / 1e6, est / 1e6)
        assert peak >= est / 8, (nu, peak / 1e6, est / 1e6)


def test_working_memory_does_not_grow_with_the_queries():
    """Beyond the output, the peak of 200,000 queries is that of 20,000 (one chunk's
    working arrays), and chunked results equal the one-block results."""
    P = RNG.random((2000, 3))
    f = np.sin(P.sum(1))
    small = GERBSInterpolator(P, f, memory_budget=40e6)
    X = RNG.random((200_000, 3)) * 0.8 + 0.1
    _, p1 = _peak(lambda: small(X[:20_000]))
    _, p2 = _peak(lambda: small(X))
    extra = 8 * 180_000 * (1 + 3 + 2)                     # output, ordering, query copy
    assert p2 <= p1 + extra * 1.5
    whole = GERBSInterpolator(P, f, memory_budget=4e9, chunk_size=10 ** 6)
    np.testing.assert_array_equal(small(X[:30_000]), whole(X[:30_000]))
