"""The memory guard (issue 7 item 2): a configurable budget, an error stating the
estimate, refusal before allocating, and an estimate that is honest.

Honest means, for the tracemalloc peak of a stencil or tessellation (numpy buffers
are traced) measured here on Suzanne and a triangle sphere:

    peak <= estimate + 32 MB        (the constant: chunked working arrays, ~20 MB)
    estimate <= 8 * peak            (an upper bound, not a wild one)

scripts/measure_memory.py measures the same at ~1M points (docs/robustness.md:
estimate 2.5 GB, tracemalloc peak 0.65 GB, RSS peak 0.78 GB for the stencil).
"""
import re
import tracemalloc

import numpy as np
import pytest

from gerbs_core import BlendingSurface
from gerbs_core.datasets import primitives
from gerbs_core.errors import GERBSValueError, ResourceLimitError
from gerbs_core.mesh.lattice import output_counts

SLACK = 32e6
FACTOR = 8.0


def _estimate(surface, resolution):
    """The guard's estimate in bytes, as stated by its error for a 1-byte budget."""
    tight = surface.with_positions(surface.vertices)
    tight.memory_budget = 1.0
    with pytest.raises(ResourceLimitError) as info:
        tight.lattice(resolution)
    msg = str(info.value)
    P, _ = output_counts(surface.topology, resolution)
    assert f"{P} points" in msg and "memory_budget" in msg
    return float(re.search(r"estimated memory (\d+) MB", msg).group(1)) * 1e6


def _peak(fn):
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = fn()
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    return out, peak


@pytest.mark.parametrize("mesh,resolution", [("suzanne", 8), ("icosphere", 12)])
@pytest.mark.parametrize("stage", ["stencil", "tessellate"])
def test_estimate_is_an_honest_bound_of_the_measured_peak(mesh, resolution, stage):
    X, faces = primitives.suzanne() if mesh == "suzanne" else primitives.icosphere(3)
    surface = BlendingSurface(X, faces)
    est = _estimate(surface, resolution)
    out, peak = _peak(lambda: getattr(surface, stage)(resolution))
    P, _ = output_counts(surface.topology, resolution)
    pts = out.apply(X) if stage == "stencil" else out[0]
    assert pts.shape == (P, 3) and np.all(np.isfinite(pts))
    assert peak <= est + SLACK, (peak, est)
    assert est <= FACTOR * peak, (peak, est)


@pytest.mark.parametrize("stage", ["stencil", "tessellate", "lattice"])
def test_over_budget_is_refused_before_allocating(stage):
    X, faces = primitives.suzanne()
    surface = BlendingSurface(X, faces, memory_budget=50e6)
    r = 2000  # ~2e9 points: would need terabytes
    with pytest.raises(ResourceLimitError) as info:
        _peak(lambda: getattr(surface, stage)(r))
    msg = str(info.value)
    assert f"resolution {r}" in msg and "exceeds the budget 50 MB" in msg
    est = float(re.search(r"estimated memory (\d+) MB", msg).group(1)) * 1e6
    assert est > 1e12
    # nothing of that size was touched: the refusal costs (almost) nothing
    tracemalloc.start()
    try:
        with pytest.raises(ResourceLimitError):
            getattr(surface, stage)(r)
        assert tracemalloc.get_traced_memory()[1] < 2e6
    finally:
        tracemalloc.stop()
    assert isinstance(info.value, GERBSValueError)


def test_budget_is_configurable_per_surface():
    X, faces = primitives.suzanne()
    r = 8
    est = _estimate(BlendingSurface(X, faces), r)
    below = BlendingSurface(X, faces, memory_budget=0.5 * est)
    with pytest.raises(ResourceLimitError, match=f"estimated memory {est / 1e6:.0f} MB"):
        below.stencil(r)
    above = BlendingSurface(X, faces, memory_budget=2.0 * est)
    assert above.stencil(r).shape[0] == output_counts(above.topology, r)[0]


def test_default_budget_refuses_absurd_resolutions_with_python_int_counts():
    """Counts are exact Python ints (no int64 overflow) even for absurd resolutions."""
    X, faces = primitives.icosphere(1)
    surface = BlendingSurface(X, faces)
    with pytest.raises(ResourceLimitError, match="points"):
        surface.tessellate(10**9)
