"""Working-memory accounting of the scattered interpolator's evaluation.

Evaluation runs over query chunks whose rows are sized from the candidate count K
of each block, so the working arrays of one chunk stay within ``work_bytes``;
the memory a call needs is then the output plus the inputs' reordering plus one
chunk, which :func:`call_estimate` states before anything is allocated.
The byte counts below are upper bounds calibrated with tracemalloc (see
tests/core/test_scattered_memory.py), not exact.
"""
from __future__ import annotations

import numpy as np

from ..errors import ResourceLimitError

__all__ = ["row_bytes", "call_estimate", "check_budget", "spatial_order"]


def row_bytes(K, n, V, nu, coefs, pairs=0):
    """Bytes of working arrays per query row with K candidates (upper bound).

    ``coefs``: Taylor coefficients per point and value gathered per candidate;
    ``pairs``: (star, corner) pairs per row of the n-D star gauge (0 otherwise).
    """
    jet = 1 + (n if nu >= 1 else 0) + (n * n if nu >= 2 else 0)
    taylor = V * coefs
    per_cand = 8 * (4 * n + 10 * jet + 3 * taylor + 3 * V * jet) + 32
    per_pair = 8 * ((n + 1) * n + 3 * (n + 1) + 8)
    return int(K * per_cand + pairs * per_pair + 8 * V * jet * 2 + 64)


def call_estimate(M, n, V, nu, work_bytes):
    """Bytes an evaluation of M queries needs at peak: output + ordering + one chunk."""
    out = 8 * M * V * n ** nu
    inputs = 8 * M * (n + 2)
    return int(out + inputs + work_bytes)


def check_budget(M, n, V, nu, work_bytes, budget):
    """Raise ResourceLimitError (naming ``memory_budget``) before allocating."""
    est = call_estimate(M, n, V, nu, work_bytes)
    if est > budget:
        raise ResourceLimitError(
            f"{M} queries with nu={nu}: estimated memory {est / 1e6:.0f} MB exceeds the "
            f"budget {budget / 1e6:.0f} MB (memory_budget); evaluate fewer points per call")
    return est


def spatial_order(x, cells_per_axis):
    """A permutation visiting x (M, n) along a Morton (Z-order) curve of a grid with
    ``cells_per_axis`` cells per axis: point location walks and neighbour gathers
    then stay local for unordered queries."""
    M, n = x.shape
    bits = max(1, min(int(np.ceil(np.log2(max(cells_per_axis, 2)))), 62 // n))
    lo, hi = x.min(0), x.max(0)
    q = ((x - lo) / np.maximum(hi - lo, 1e-300) * ((1 << bits) - 1)).astype(np.int64)
    code = np.zeros(M, np.int64)
    for b in range(bits - 1, -1, -1):
        for a in range(n):
            code = (code << 1) | ((q[:, a] >> b) & 1)
    return np.argsort(code, kind="stable")
