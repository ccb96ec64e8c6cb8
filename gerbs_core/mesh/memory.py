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
"""
from __future__ import annotations

import numpy as np

__all__ = ["memory_estimate", "work_bytes", "evaluation_chunk", "assembly_chunk",
           "face_step_bytes", "BYTES_PER_SAMPLE", "BYTES_PER_ENTRY", "BYTES_PER_VERTEX",
           "CHUNK_BYTES",
           "MIN_WORK_BYTES", "WORK_FRACTION", "BYTES_PER_TERM", "ASSEMBLY_BYTES_PER_TERM"]

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
