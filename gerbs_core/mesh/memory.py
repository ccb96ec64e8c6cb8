"""Memory model of a tessellation / stencil, checked against a surface's memory budget.

Peak ~ P (bytes per sample + bytes per stencil entry) + the chunked
working set of the evaluation (:data:`gerbs_core.mesh.evaluate.CHUNK`). The entries
per sample are those of the factors B and E (:mod:`gerbs_core.mesh.stencil`):
n corners x (1 + M) with M the coefficients of the corners' degrees. An upper
bound: scripts/measure_memory.py compares it with measured peaks.
"""
from __future__ import annotations

import numpy as np

__all__ = ["memory_estimate", "BYTES_PER_SAMPLE", "BYTES_PER_NNZ", "CHUNK_BYTES"]

BYTES_PER_SAMPLE = 700   # points, normals, lattice and per-sample arrays (with margin)
BYTES_PER_NNZ = 40       # assembly: COO (two int64 indices + float64), then CSR (float64 + index)
CHUNK_BYTES = 64e6       # working arrays of one evaluation chunk at nu = 1, degree 4


def memory_estimate(model, resolution: int) -> int:
    """Bytes a tessellation or stencil of ``model`` at ``resolution`` needs at peak."""
    from .lattice import output_counts
    topo = model.topology
    P, _ = output_counts(topo, resolution)
    d = np.asarray(model.degrees, dtype=np.float64)
    m_avg = float(np.mean(d * (d + 3) / 2))
    n_avg = float(np.mean(topo.face_sizes))
    nnz = n_avg * (1.0 + m_avg)
    return int(P * (BYTES_PER_SAMPLE + BYTES_PER_NNZ * nnz) + CHUNK_BYTES
               + BYTES_PER_NNZ * model.fits.nnz_estimate)
