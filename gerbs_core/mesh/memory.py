"""Memory model of a tessellation / stencil, checked against a surface's memory budget.

Peak ~ P (bytes per sample + bytes per stencil entry x entries per sample) + the
chunked working set of the evaluation (:data:`gerbs_core.mesh.evaluate.CHUNK`). The
entries per sample are those of the factors B and E (:mod:`gerbs_core.mesh.stencil`):
n corners x (1 + M) with M the coefficients of the corners' degrees, written in place
as csr (float64 value + int32 index, :mod:`gerbs_core.mesh.assembly`). The
coefficients are applied as a map (:class:`gerbs_core.mesh.coupling.CoupledFits`;
partial updates take single columns), so no explicit coefficient operator is held.
An upper bound: scripts/measure_memory.py compares it with measured peaks.
"""
from __future__ import annotations

import numpy as np

__all__ = ["memory_estimate", "BYTES_PER_SAMPLE", "BYTES_PER_ENTRY", "CHUNK_BYTES"]

# measured 227 B per sample besides the factors (lattice, points, row pointers), margin 30%
BYTES_PER_SAMPLE = 300
BYTES_PER_ENTRY = 16      # csr entry of B or E: float64 value + int32 index (12 B), margin
CHUNK_BYTES = 64e6        # working arrays of one evaluation chunk at nu = 1, degree 4


def memory_estimate(model, resolution: int) -> int:
    """Bytes a tessellation or stencil of ``model`` at ``resolution`` needs at peak."""
    from .lattice import output_counts
    topo = model.topology
    P, _ = output_counts(topo, resolution)
    d = np.asarray(model.degrees, dtype=np.float64)
    m_avg = float(np.mean(d * (d + 3) / 2))
    n_avg = float(np.mean(topo.face_sizes))
    nnz = n_avg * (1.0 + m_avg)
    return int(P * (BYTES_PER_SAMPLE + BYTES_PER_ENTRY * nnz) + CHUNK_BYTES)
