"""Memory model of a tessellation / stencil, checked against a surface's memory budget.

Peak ~ P (bytes per sample + bytes per stencil entry x entries per sample) + V bytes
per vertex (the coefficient map's application ``fits(X)`` and the stencil's per-vertex
tables: measured ~3.3 kB per vertex) + the working set of one evaluation step. The entries per sample are those of the factors B
and E (:mod:`gerbs_core.mesh.stencil`): n corners x (1 + M) with M the coefficients of
the corners' degrees, written in place as csr (float64 value + int32 index,
:mod:`gerbs_core.mesh.assembly`). The coefficients are applied as a map
(:class:`gerbs_core.mesh.coupling.CoupledFits`; partial updates take single columns),
so no explicit coefficient operator is held.

The step's working set adapts to the budget: :func:`work_bytes` = a quarter of it,
between ``MIN_WORK_BYTES`` and ``CHUNK_BYTES``; the evaluation (:mod:`.evaluate`) and
the assembly (:mod:`.assembly`) take as many sample x corner terms per step as fit in
it (:func:`evaluation_chunk`, :func:`assembly_chunk`). A step holds at least one face,
so the estimate counts the larger of the working set and one face's step
(:func:`face_step_bytes`). The step size never changes a bit of the results (every
face's, every sample's values are computed alone). An upper bound: tests/core/
test_memory_guard.py and scripts/measure_memory.py compare it with measured peaks.

The construction (the model: layouts to coupled fits) has its own bound,
:func:`build_estimate`, checked by :func:`check_build` before the stages it bounds: it is
dominated by the ring data on ordinary meshes and by n^3 on faces of many corners.
"""
from __future__ import annotations

import numpy as np

from ..errors import ResourceLimitError

__all__ = ["memory_estimate", "build_estimate", "check_build", "work_bytes",
           "evaluation_chunk", "assembly_chunk",
           "face_step_bytes", "BYTES_PER_SAMPLE", "BYTES_PER_ENTRY", "BYTES_PER_VERTEX",
           "CHUNK_BYTES",
           "MIN_WORK_BYTES", "WORK_FRACTION", "BYTES_PER_TERM", "ASSEMBLY_BYTES_PER_TERM",
           "megabytes"]

# measured 227 B per sample besides the factors (lattice, points, row pointers), margin 30%
BYTES_PER_SAMPLE = 300
BYTES_PER_ENTRY = 16      # csr entry of B or E: float64 value + int32 index (12 B), margin
BYTES_PER_VERTEX = 4000   # fits(X) (V, MMAX, 3) temporaries: measured <= 3.3 kB, margin
CHUNK_BYTES = 64e6        # working set of one evaluation / assembly step at most
MIN_WORK_BYTES = 0.5e6    # ... at least (smaller steps only add Python overhead)
WORK_FRACTION = 0.25      # ... else this share of the memory budget
# working arrays per padded (sample, corner) term of an evaluation step at nu = 0, 1, 2
# (measured on Suzanne, a grid and an icosphere, degrees up to 4: <= ~600, 1400, 3400 B)
BYTES_PER_TERM = (800, 1600, 4000)
ASSEMBLY_BYTES_PER_TERM = 400   # of an assembly step (measured <= ~330 B), margin
# the construction (layouts, charts, cover, candidate fits, choice, coupling), measured
# with tracemalloc (docs/robustness.md): a fixed part, per ring datum (rings 1-2 of every
# vertex: 2.2 kB on grids, 2.7 kB on a 35k triangle mesh and an icosphere, 3.4 kB on
# Suzanne with the fixed part) and per n^3 of every face of n corners (every corner of an
# n-gon is active almost everywhere in it and reads all the others: one 128 / 256 / 384-gon
# 0.19 / 1.37 / 4.43 GB, 67-69 B per n^3); the n^2 part is the stages before the fits
# (a 1024-gon: 0.19 GB before its fits)
BUILD_BASE_BYTES = 32e6
BUILD_BYTES_PER_DATUM = 3000
BUILD_BYTES_PER_N3 = 75
BUILD_BYTES_PER_N2 = 250
# the construction is needed by every output, so a small budget (sized for the output:
# down to 1 MB in the add-on) does not refuse it: it may use the larger of the budget and
# this (the default budget)
BUILD_MIN_BUDGET = 2.0e9
# the fairing (mesh.fairing) per point of its lattice: the values, the factor's columns of
# the corrected coefficients and the optimiser's arrays (measured 2026-12-06: Suzanne 1.9 kB
# a point at peak over the build without it, 29 -> 87 MB traced; the cow 0.8 kB), with a margin
FAIRING_BYTES_PER_POINT = 4000


def megabytes(b) -> str:
    """A byte count in MB for messages (the add-on's budget is set in MB): three
    significant digits below 100 MB, whole MB above, never in exponent form. An estimate
    of 1.4e6 bytes against a budget of 1e6 read "1 MB exceeds the budget 1 MB" (a stress
    test); now "1.4 MB exceeds the budget 1 MB"."""
    x = float(b) / 1e6
    return f"{x:.0f} MB" if x >= 100 else f"{x:.3g} MB" if x >= 1e-3 else f"{x:.1e} MB"


def work_bytes(budget=None) -> float:
    """Working set of one step for a memory ``budget`` in bytes (None: ``CHUNK_BYTES``)."""
    if budget is None:
        return CHUNK_BYTES
    return min(CHUNK_BYTES, max(MIN_WORK_BYTES, WORK_FRACTION * float(budget)))


def evaluation_chunk(budget, nu: int) -> int:
    """Padded sample x corner terms per evaluation step with derivatives up to ``nu``."""
    return max(1, int(work_bytes(budget) // BYTES_PER_TERM[nu]))


def assembly_chunk(budget, n_max: int) -> int:
    """Samples per assembly step on faces of at most ``n_max`` corners."""
    from .assembly import CHUNK_SAMPLES
    per = int(work_bytes(budget) // (ASSEMBLY_BYTES_PER_TERM * max(int(n_max), 1)))
    return max(1, min(CHUNK_SAMPLES, per))


def _face_points(n: int, r: int) -> int:
    """Distinct samples of one n-gon at resolution r, its border included (Python int)."""
    if n == 3:
        return (r + 1) * (r + 2) // 2
    if n == 4:
        return (r + 1) ** 2
    return 1 + n * (2 * r - 1) + n * (r - 1) * (r - 2) // 2


def face_step_bytes(topology, resolution: int) -> int:
    """Working set of the smallest evaluation step, one face (the largest's samples x
    its corners, at nu = 1): a step never splits a face."""
    r = int(resolution)
    return max(n * _face_points(n, r) * BYTES_PER_TERM[1]
               for n in np.unique(np.asarray(topology.face_sizes)).tolist())


def memory_estimate(model, resolution: int, budget=None) -> int:
    """Bytes a tessellation or stencil of ``model`` at ``resolution`` needs at peak, with
    its steps sized for ``budget`` (:func:`work_bytes`)."""
    from .lattice import output_counts
    topo = model.topology
    P, _ = output_counts(topo, resolution)
    d = np.asarray(model.degrees, dtype=np.float64)
    m_avg = float(np.mean(d * (d + 3) / 2))
    n_avg = float(np.mean(topo.face_sizes))
    nnz = n_avg * (1.0 + m_avg)
    step = max(work_bytes(budget), face_step_bytes(topo, resolution))
    return int(P * (BYTES_PER_SAMPLE + BYTES_PER_ENTRY * nnz)
               + BYTES_PER_VERTEX * int(topo.n_vertices) + step)


def build_estimate(face_sizes, n_data: int = 0) -> int:
    """Bytes the construction of a surface needs at peak (an upper bound, within 5-80 % of
    the measured peaks: see the constants), from the faces' sizes (F,) and the number of
    ring data ``n_data`` (0 before the rings are known: the part the faces alone give)."""
    n = np.asarray(face_sizes, dtype=np.float64)
    return int(BUILD_BASE_BYTES + BUILD_BYTES_PER_N2 * np.sum(n ** 2)
               + BUILD_BYTES_PER_N3 * np.sum(n ** 3) + BUILD_BYTES_PER_DATUM * int(n_data))


def check_build(face_sizes, budget: float, n_data: int = 0) -> None:
    """ResourceLimitError naming the estimate, the limit and the largest face when
    :func:`build_estimate` exceeds the larger of ``budget`` and ``BUILD_MIN_BUDGET``:
    checked before the stages it bounds, so a mesh with huge n-gons is refused before it
    allocates (a 512-gon would take ~10 GB, a 1024-gon ~80 GB), never run into the
    machine's memory."""
    est = build_estimate(face_sizes, n_data)
    limit = max(float(budget), BUILD_MIN_BUDGET)
    if est <= limit:
        return
    n = np.asarray(face_sizes, dtype=np.float64)
    hint = (f"; its largest face has {int(n.max())} corners and the build's memory grows as "
            f"the cube of a face's corners: split large faces (Triangulate or Poke Faces)"
            if BUILD_BYTES_PER_N3 * np.sum(n[n > 4] ** 3) > 0.25 * est else "")
    raise ResourceLimitError(f"the surface build needs an estimated {megabytes(est)}, over "
                             f"the limit {megabytes(limit)} (memory_budget, at least "
                             f"{megabytes(BUILD_MIN_BUDGET)} for the build){hint}")


def fairing_estimate(n_points: int) -> int:
    """Bytes the fairing (:mod:`gerbs_core.mesh.fairing`) adds at peak on a lattice of
    ``n_points`` points (the faces it looks at)."""
    return int(FAIRING_BYTES_PER_POINT * n_points)
