"""The memory guard (issue 7 item 2): a configurable budget, an error stating the
estimate, refusal before allocating, and an estimate that is honest.

Honest means, for the tracemalloc peak of a stencil or tessellation (numpy buffers
are traced) measured here on Suzanne and a triangle sphere:

    peak <= estimate + 32 MB        (the constant: chunked working arrays, ~20 MB)
    estimate <= 8 * peak            (an upper bound, not a wild one)

With small budgets the evaluation steps shrink (gerbs_core.mesh.memory.work_bytes): a
small mesh builds within 1e6 bytes, its measured peak within the estimate, and the
step size changes no bit of the result.

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
from gerbs_core.mesh.memory import megabytes

SLACK = 32e6
FACTOR = 8.0


def _estimate(surface, resolution):
    """The guard's estimate in bytes (for the surface's own budget: the evaluation steps
    are sized for it), and the refusal of a surface whose budget is below it states it."""
    est = surface.memory_estimate(resolution)
    tight = surface.with_positions(surface.vertices)
    tight._cache("memory_budget", 1.0)  # (immutable: the cache writer, for this check only)
    with pytest.raises(ResourceLimitError) as info:
        tight.lattice(resolution)
    msg = str(info.value)
    P, _ = output_counts(surface.topology, resolution)
    assert f"{P} points" in msg and "memory_budget" in msg
    stated = float(re.search(r"estimated memory ([\d.]+) MB", msg).group(1)) * 1e6
    assert abs(stated - tight.memory_estimate(resolution)) <= 0.5e6
    return est


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
    est = float(re.search(r"estimated memory ([\d.]+) MB", msg).group(1)) * 1e6
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
    below = BlendingSurface(X, faces, memory_budget=0.3 * est)
    own = below.memory_estimate(r)      # its steps are smaller, the output is not
    assert 0.3 * est < own < est
    with pytest.raises(ResourceLimitError, match=f"estimated memory {megabytes(own)}"):
        below.stencil(r)
    above = BlendingSurface(X, faces, memory_budget=2.0 * est)
    assert above.stencil(r).shape[0] == output_counts(above.topology, r)[0]


def test_default_budget_refuses_absurd_resolutions_with_python_int_counts():
    """Counts are exact Python ints (no int64 overflow) even for absurd resolutions."""
    X, faces = primitives.icosphere(1)
    surface = BlendingSurface(X, faces)
    with pytest.raises(ResourceLimitError, match="points"):
        surface.tessellate(10**9)


def _warm_peak(fn):
    """tracemalloc peak of fn() run a second time (the first pays one-off imports and
    template caches, which no budget is about)."""
    fn()
    return _peak(fn)


@pytest.mark.parametrize("mesh,resolution,budget", [("icosphere1", 2, 1e6), ("cube", 4, 1e6),
                                                     ("suzanne", 2, 6e6)])
def test_a_small_mesh_builds_within_a_small_budget(mesh, resolution, budget):
    """Budgets down to the add-on's and the CLI's minimum (1e6 bytes) build small meshes
    (the evaluation steps shrink with the budget: a fixed 64 MB step refused every mesh
    below ~64 MB), the measured peak stays within the estimate and the budget, and the
    result is bit for bit the default budget's."""
    X, faces = {"icosphere1": primitives.icosphere(1), "cube": primitives.icosphere(0),
                "suzanne": primitives.suzanne()}[mesh]
    small = BlendingSurface(X, faces, memory_budget=budget)
    big = BlendingSurface(X, faces)
    est = small.memory_estimate(resolution)
    assert est <= budget
    for stage in ("stencil", "tessellate"):
        run = (lambda s: s.stencil(resolution).apply(X)) if stage == "stencil" else \
            (lambda s: s.tessellate(resolution))
        out, peak = _warm_peak(lambda: run(small))
        assert peak <= est <= budget, (stage, peak, est)
        ref = run(big)
        for a, b in zip(out if stage == "tessellate" else [out],
                        ref if stage == "tessellate" else [ref]):
            assert np.array_equal(a, b), stage       # bit for bit


def test_the_step_size_never_changes_a_bit():
    """Evaluation (nu = 0, 1, 2) and the stencil's factors at step sizes from one face to
    all at once: the same bits (Suzanne: mixed degrees 2..4 across the steps)."""
    from gerbs_core.mesh.assembly import assemble
    from gerbs_core.mesh.evaluate import evaluate

    X, faces = primitives.suzanne()
    s = BlendingSurface(X, faces)
    lat = s.lattice(3)
    x = lat.map_to_polygon(s.layouts.corners)
    for nu in (0, 1, 2):
        ref, eps = evaluate(s.model, s.vertices, s.coefficients, lat.face, x, nu, 10**9)
        for chunk in (1, 500, 20_000):
            out, e = evaluate(s.model, s.vertices, s.coefficients, lat.face, x, nu, chunk)
            assert e == eps and all(np.array_equal(a, b) for a, b in zip(out, ref))
    B0, E0, eps0 = assemble(s.model, lat, 10**9)
    for chunk in (1, 777):
        B, E, eps = assemble(s.model, lat, chunk)
        assert eps == eps0
        for m, m0 in ((B, B0), (E, E0)):
            assert np.array_equal(m.indptr, m0.indptr) and np.array_equal(m.indices, m0.indices)
            assert np.array_equal(m.data, m0.data)


def test_a_mesh_too_large_for_a_small_budget_is_still_refused():
    X, faces = primitives.suzanne()
    surface = BlendingSurface(X, faces, memory_budget=1e6)
    for stage in ("stencil", "tessellate"):
        with pytest.raises(ResourceLimitError, match=r"resolution 4: \d+ points, estimated "
                           r"memory [\d.]+ MB exceeds the budget 1 MB \(memory_budget\)"):
            getattr(surface, stage)(4)


def test_steps_are_sized_for_the_budget():
    """A quarter of the budget, between the floor and the default step (64 MB); the
    estimate counts one whole face when a face's step is larger (high resolutions)."""
    from gerbs_core.mesh import memory

    assert memory.work_bytes(1e6) == memory.MIN_WORK_BYTES
    assert memory.work_bytes(40e6) == 10e6
    assert memory.work_bytes(2e9) == memory.CHUNK_BYTES
    assert memory.evaluation_chunk(40e6, 2) < memory.evaluation_chunk(40e6, 1) \
        < memory.evaluation_chunk(40e6, 0)
    X, faces = primitives.icosphere(0)
    s = BlendingSurface(X, faces, memory_budget=1e6)
    r = 40           # one triangle's step: 861 samples x 3 corners x 1600 B = 4.1 MB
    step = memory.face_step_bytes(s.topology, r)
    assert step == 3 * 861 * memory.BYTES_PER_TERM[1]
    assert step > memory.work_bytes(1e6)
    # the same output with 64 MB steps: the estimates differ by the steps exactly
    diff = memory.memory_estimate(s.model, r, None) - s.memory_estimate(r)
    assert abs(diff - (memory.CHUNK_BYTES - step)) <= 1


def _circle(n):
    t = 2 * np.pi * np.arange(n) / n
    return np.c_[np.cos(t), np.sin(t), 0 * t], [list(range(n))]


def _cylinder(n):
    t = 2 * np.pi * np.arange(n) / n
    ring = np.c_[np.cos(t), np.sin(t)]
    V = np.r_[np.c_[ring, -np.ones(n)], np.c_[ring, np.ones(n)]]
    F = [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    return V, F + [list(range(n))[::-1], list(range(n, 2 * n))]


@pytest.mark.parametrize("mesh", ["suzanne", "cylinder64", "circle128"])
def test_the_build_estimate_bounds_the_measured_build_peak(mesh):
    """gerbs_core.mesh.memory.build_estimate (faces and ring data) against the tracemalloc
    peak of the construction: an upper bound, and not a wild one (a 128-gon's build is
    dominated by its n^3 term: 191 MB measured)."""
    from gerbs_core.mesh.memory import build_estimate, fairing_estimate
    from gerbs_core.mesh.rings import data_rings

    X, faces = {"suzanne": primitives.suzanne(), "cylinder64": _cylinder(64),
                "circle128": _circle(128)}[mesh]
    s, peak = _peak(lambda: BlendingSurface(X, faces))
    m = s.model
    est = build_estimate(m.topology.face_sizes,
                         len(data_rings(m.topology, m.charts, m.layouts.corners).ids)) \
        + fairing_estimate(m.fairing_points)
    assert peak <= est <= 3.0 * peak, (peak, est)


def test_a_huge_ngon_is_refused_before_its_build_allocates():
    """One 512-gon would need ~10 GB to build (a 384-gon: 4.4 GB measured): refused at
    once, naming the estimate, the limit and the remedy, having allocated almost nothing;
    a larger budget lets the same check pass (it is the budget's, not a size cap)."""
    from gerbs_core.mesh.memory import build_estimate, check_build

    X, faces = _circle(512)
    with pytest.raises(ResourceLimitError, match=r"needs an estimated [\d.]+ MB, over the limit "
                       r"2000 MB \(memory_budget.*largest face has 512 corners.*Poke Faces"):
        BlendingSurface(X, faces)
    tracemalloc.start()
    try:
        with pytest.raises(ResourceLimitError):
            BlendingSurface(X, faces)
        assert tracemalloc.get_traced_memory()[1] < 20e6
    finally:
        tracemalloc.stop()
    # a small budget (for the output) does not refuse an ordinary build; a large one
    # raises the build's limit
    BlendingSurface(*primitives.suzanne(), memory_budget=1e6)
    check_build([512], 2 * build_estimate([512]))
    with pytest.raises(ResourceLimitError):
        check_build([512], 0.5 * build_estimate([512]))


def test_memory_in_messages_tells_an_estimate_from_the_budget_it_exceeds():
    """A stress test (2026-12-07): a 16-segment Cylinder against a 1 MB budget read
    "estimated memory 1 MB exceeds the budget 1 MB" (both rounded to whole MB)."""
    assert [megabytes(b) for b in (1.4e6, 1e6, 12.34e6, 2.57e9, 4.07e12, 2e2)] == \
        ["1.4 MB", "1 MB", "12.3 MB", "2570 MB", "4070000 MB", "2.0e-04 MB"]
    X, faces = primitives.cylinder(16) if hasattr(primitives, "cylinder") else primitives.suzanne()
    surface = BlendingSurface(X, faces, memory_budget=1e6)
    with pytest.raises(ResourceLimitError) as info:
        surface.stencil(8)
    stated = re.search(r"estimated memory ([\d.]+) MB exceeds the budget 1 MB", str(info.value))
    assert stated is not None and float(stated.group(1)) > 1.0, str(info.value)
